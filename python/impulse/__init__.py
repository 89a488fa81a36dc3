# SPDX-License-Identifier: Apache-2.0
"""impulse: animated procedural textures from sparse convolution noise (Lewis 1986), rendered to
numpy arrays. The package `pip install .` makes: the compiled module (impulse.impulse) and the
built-in scenes it loads by name (impulse/scenes). README "Python" documents the API."""
import os as _os

from . import impulse as _module
from .impulse import *  # noqa: F401,F403 (the module's API is the package's)

__doc__ = _module.__doc__
_module._set_builtin_scene_dir(_os.path.join(_os.path.dirname(__file__), "scenes"))

# Classes and exceptions named as the build tree's module names them (impulse.SceneError).
for _value in list(globals().values()):
    if isinstance(_value, type) and _value.__module__ == _module.__name__:
        _value.__module__ = __name__
