# SPDX-License-Identifier: Apache-2.0
# Bakes a small Mantaflow smoke simulation in headless Blender, for blender/test_mantaflow.sh:
#   blender -b --factory-startup --python-exit-code 1 --python bake_mantaflow.py -- CACHE_DIR [RES [FRAMES]]
# A gas domain, the cube [-1, 1]^3 (2 Blender units), RES voxels along its longest side, and a
# sphere of smoke inflowing off-centre near the floor with an initial velocity up and to the
# right, so the plume rises, leans and spreads: a vertical slice through it diverges in 2-D.
# Debian's Blender 3.4 cannot run fluid.bake_all() headless, so the frames are stepped with a
# REPLAY cache (scene.frame_set), which writes CACHE_DIR/data/fluid_data_####.vdb
# (velocity, density, temperature, flame, shadow). Prints the domain's facts and the bake's time
# as "mantaflow: key value" lines the test reads.
import sys
import time

import bpy
import numpy as np

args = sys.argv[sys.argv.index("--") + 1:]
cache = args[0]
resolution = int(args[1]) if len(args) > 1 else 32
frames = int(args[2]) if len(args) > 2 else 24

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.frame_start, scene.frame_end = 1, frames
scene.render.fps, scene.render.fps_base = 24, 1.0

bpy.ops.mesh.primitive_cube_add(size=2.0, location=(0.0, 0.0, 0.0))
domain = bpy.context.object
domain.name = "Domain"
fluid = domain.modifiers.new("Fluid", "FLUID")
fluid.fluid_type = "DOMAIN"
d = fluid.domain_settings
d.domain_type = "GAS"
d.resolution_max = resolution
d.cache_type = "REPLAY"
d.cache_data_format = "OPENVDB"
d.cache_directory = cache
d.cache_frame_start, d.cache_frame_end = 1, frames
d.use_adaptive_domain = False
# 0: no voxel is dropped from the cache as empty. Mantaflow still stores the velocity only where
# there is smoke, so each frame's grid covers its own box (impulse reads the frames over the union
# of their boxes: docs/scenes.md "A Blender cache")
d.clipping = 0.0

bpy.ops.mesh.primitive_uv_sphere_add(radius=0.25, location=(-0.35, 0.0, -0.6))
source = bpy.context.object
source.name = "Inflow"
inflow = source.modifiers.new("Fluid", "FLUID")
inflow.fluid_type = "FLOW"
f = inflow.flow_settings
f.flow_type = "SMOKE"
f.flow_behavior = "INFLOW"
f.flow_source = "MESH"
f.use_initial_velocity = True
f.velocity_coord = (1.5, 0.0, 2.0)  # Blender units per second

# Blender's own view of each frame's velocity (FluidDomainSettings.velocity_grid, the solver's
# grid as the viewport draws it, x fastest, then y, then z), kept beside the cache as the truth
# the test compares with, independent of impulse's VDB reader.
t0 = time.perf_counter()
velocities, densities = [], []
for frame in range(1, frames + 1):
    scene.frame_set(frame)
    # the solver's grids live on the evaluated copy of the domain (the original's crash)
    evaluated = domain.evaluated_get(bpy.context.evaluated_depsgraph_get())
    grids = evaluated.modifiers["Fluid"].domain_settings
    velocities.append(np.array(grids.velocity_grid, dtype=np.float32))
    densities.append(np.array(grids.density_grid, dtype=np.float32))
seconds = time.perf_counter() - t0
evaluated = domain.evaluated_get(bpy.context.evaluated_depsgraph_get()).modifiers["Fluid"].domain_settings
nx, ny, nz = evaluated.domain_resolution
np.save(f"{cache}/blender_velocity.npy", np.stack(velocities).reshape(frames, nz, ny, nx, 3))
np.save(f"{cache}/blender_density.npy", np.stack(densities).reshape(frames, nz, ny, nx))

print(f"mantaflow: resolution {resolution}")
print(f"mantaflow: frames {frames}")
print(f"mantaflow: fps {scene.render.fps / scene.render.fps_base}")
print(f"mantaflow: domain_resolution {nx} {ny} {nz}")
print(f"mantaflow: bake_seconds {seconds:.2f}")
