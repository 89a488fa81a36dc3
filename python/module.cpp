// SPDX-License-Identifier: Apache-2.0
// The Python module `impulse`: scenes rendered to numpy arrays, their closed-form theory, and
// the analysis of any frames (README "Python"). Errors are Python exceptions carrying the
// library's one-line messages; the GIL is released while a frame renders.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>

#include "analysis/analysis.h"
#include "numeric/errors.h"
#include "python/scene_object.h"
#include "scenes/scenes.h"

namespace py = pybind11;

namespace impulse::python {
namespace {

/// float32, C order; forcecast converts float64 (float_array refuses other types first).
using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

/// A Python value as the text of a `--set key=value` override: strings as the CLI takes them
/// (a bare word is a string, "8" a number), numbers, booleans and lists as TOML.
std::string toml_value(const py::handle& v) {
    if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
    if (py::isinstance<py::int_>(v) || py::isinstance<py::float_>(v)) {
        const std::string r = py::repr(v).cast<std::string>();
        return r == "inf" ? "inf" : r == "-inf" ? "-inf" : r;
    }
    if (py::isinstance<py::str>(v)) return v.cast<std::string>();
    if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v)) {
        std::string s = "[";
        for (const py::handle& e : v) {
            const std::string item =
                py::isinstance<py::str>(e) ? "\"" + e.cast<std::string>() + "\"" : toml_value(e);
            s += (s.size() > 1 ? ", " : "") + item;
        }
        return s + "]";
    }
    throw ValueError("override value " + py::repr(v).cast<std::string>() +
                     ": expected a number, a bool, a string or a list of them");
}

/// `overrides` as --set strings: a dict {key: value} or a list of "key=value" strings.
std::vector<std::string> override_strings(const py::object& overrides) {
    std::vector<std::string> out;
    if (overrides.is_none()) return out;
    if (py::isinstance<py::dict>(overrides)) {
        for (const auto& [k, v] : overrides.cast<py::dict>())
            out.push_back(py::str(k).cast<std::string>() + "=" + toml_value(v));
        return out;
    }
    if (py::isinstance<py::str>(overrides))
        throw ValueError(
            "overrides: expected a dict {key: value} or a list of \"key=value\", "
            "got the string " +
            py::repr(overrides).cast<std::string>());
    for (const py::handle& o : overrides) out.push_back(py::str(o).cast<std::string>());
    return out;
}

/// True when `source` is TOML text rather than a file name or a built-in scene's name.
bool is_toml_text(const std::string& source) {
    return source.find('\n') != std::string::npos || source.find('=') != std::string::npos;
}

std::shared_ptr<SceneObject> load(const std::string& source, const py::object& overrides,
                                  const py::object& size) {
    std::vector<std::string> sets = override_strings(overrides);
    scenes::OutputSize s;
    if (!size.is_none()) {
        const auto wh = size.cast<std::pair<int, int>>();
        if (wh.first < 1 || wh.second < 1 || wh.first > 32768 || wh.second > 32768)
            throw ValueError("size (" + std::to_string(wh.first) + ", " +
                             std::to_string(wh.second) +
                             "): expected (width, height) in pixels, each in [1, 32768]");
        s = {wh.first, wh.second};
    }
    scenes::Scene scene = is_toml_text(source)
                              ? scenes::load_scene_string(source, "<string>", sets, s)
                              : scenes::load_scene(scenes::resolve_scene(source), sets, s);
    return std::make_shared<SceneObject>(std::move(scene), std::move(sets));
}

/// A float32 array viewing `frame`'s pixels (H x W, or H x W x channels), owning it through a
/// capsule: no copy.
template <class Owner>
py::array_t<float> view_of(std::unique_ptr<Owner> owner, float* data, int height, int width,
                           int channels) {
    auto* raw = owner.release();
    py::capsule base(raw, [](void* p) { delete static_cast<Owner*>(p); });
    const auto c = static_cast<py::ssize_t>(channels), w = static_cast<py::ssize_t>(width);
    if (channels == 1)
        return py::array_t<float>({py::ssize_t(height), w}, {w * 4, py::ssize_t(4)}, data, base);
    return py::array_t<float>({py::ssize_t(height), w, c}, {w * c * 4, c * 4, py::ssize_t(4)}, data,
                              base);
}

py::array_t<float> render(SceneObject& s, int64_t frame) {
    std::unique_ptr<numeric::Frame> f;
    {
        py::gil_scoped_release release;  // other Python threads run while the frame renders
        f = s.render(frame);
    }
    float* data = f->data.data();
    const int h = f->height, w = f->width;
    return view_of(std::move(f), data, h, w, 1);
}

py::array_t<float> render_rgb(SceneObject& s, int64_t frame) {
    auto rgb = std::make_unique<std::vector<float>>();
    {
        py::gil_scoped_release release;
        *rgb = s.render_rgb(frame);
    }
    float* data = rgb->data();
    return view_of(std::move(rgb), data, s.scene().output.height, s.scene().output.width, 3);
}

/// A copy of a frame as a float32 H x W array.
py::array_t<float> frame_array(const numeric::Frame& f) {
    py::array_t<float> a({py::ssize_t(f.height), py::ssize_t(f.width)});
    std::copy(f.data.begin(), f.data.end(), a.mutable_data());
    return a;
}

/// The channels named in `names` (docs/channels.md) as a dict of H x W arrays keyed by their
/// EXR names: value, LAYER.value, dx, LAYER.dx, dy, LAYER.dy, N.X N.Y N.Z, forward.u ...
py::dict render_channels(SceneObject& s, int64_t frame, const std::vector<std::string>& names) {
    const scenes::ChannelSet set = scenes::parse_channels(names, "render_channels");
    scenes::FrameChannels ch;
    {
        py::gil_scoped_release release;
        ch = s.render_channels(frame, set);
    }
    py::dict d;
    auto field = [&](bool on, const char* c, const numeric::Frame& all,
                     const std::vector<numeric::Frame>& per) {
        if (!on) return;
        d[c] = frame_array(all);
        for (size_t k = 0; k < per.size(); ++k)
            d[py::str(ch.layer_names[k] + "." + c)] = frame_array(per[k]);
    };
    field(set.value, "value", ch.value, ch.layer_value);
    field(set.dx, "dx", ch.dx, ch.layer_dx);
    field(set.dy, "dy", ch.dy, ch.layer_dy);
    if (set.normal) {
        std::vector<float> xyz;
        const scenes::Scene& sc = s.scene();
        scenes::normal_map(ch.dx, ch.dy, scenes::normal_relief(sc, sc.frame_time(frame)), xyz);
        const char* axis[3] = {"N.X", "N.Y", "N.Z"};
        for (int k = 0; k < 3; ++k) {
            numeric::Frame f;
            f.resize(ch.dx.width, ch.dx.height);
            for (size_t i = 0; i < f.data.size(); ++i) f.data[i] = xyz[3 * i + k];
            d[axis[k]] = frame_array(f);
        }
    }
    if (set.motion) {
        const char* name[4] = {"forward.u", "forward.v", "backward.u", "backward.v"};
        for (int k = 0; k < 4; ++k) d[name[k]] = frame_array(ch.motion[k]);
    }
    return d;
}

/// Frequencies 0 .. 0.5 cycles per pixel in `n` steps: the range a periodogram covers.
std::vector<double> nyquist_grid(int n) {
    std::vector<double> k(size_t(n) + 1);
    for (int i = 0; i <= n; ++i) k[size_t(i)] = 0.5 * i / n;
    return k;
}

py::dict theory(const SceneObject& s, int64_t frame) {
    s.check_frame(frame);
    const double t = s.scene().frame_time(frame);
    const scenes::Theory th = scenes::scene_theory(s.scene(), t);
    py::dict d;
    d["mean"] = th.mean;
    d["variance"] = th.variance;
    d["time"] = t;
    std::string why;
    const std::vector<double> k = nyquist_grid(256);
    if (const auto p = s.spectrum(k, t, why)) {
        py::dict sp;
        sp["frequency"] = py::array_t<double>(py::ssize_t(k.size()), k.data());
        sp["power"] = py::array_t<double>(py::ssize_t(p->size()), p->data());
        d["spectrum"] = sp;
    } else {
        d["spectrum"] = py::none();
        d["spectrum_note"] = why;
    }
    return d;
}

/// The values of a float array as floats (float64 converted); anything else is refused.
FloatArray float_array(const py::handle& a, const std::string& what) {
    if (!py::isinstance<py::array>(a))
        throw ValueError(what + ": expected a numpy array, got " +
                         py::str(py::type::of(a).attr("__name__")).cast<std::string>());
    const auto arr = py::reinterpret_borrow<py::array>(a);
    const char kind = arr.dtype().kind();
    if (kind != 'f' || (arr.itemsize() != 4 && arr.itemsize() != 8))
        throw ValueError(what + ": array of dtype " + py::str(arr.dtype()).cast<std::string>() +
                         ": expected float32 or float64 values");
    FloatArray out = FloatArray::ensure(arr);
    if (!out) throw py::error_already_set();
    return out;
}

std::string shape_text(const py::array& a) {
    std::string s = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

analysis::Image image_of(const FloatArray& a) {
    analysis::Image im;
    im.height = int(a.shape(0)), im.width = int(a.shape(1));
    im.data.assign(a.data(), a.data() + a.size());
    return im;
}

/// Frames from an H x W array, an N x H x W array or a sequence of H x W arrays.
std::vector<analysis::Image> frames_of(const py::handle& frames) {
    std::vector<analysis::Image> out;
    if (!py::isinstance<py::array>(frames) && py::isinstance<py::sequence>(frames)) {
        for (const py::handle& f : frames) {
            const auto a = float_array(f, "analyze: frame " + std::to_string(out.size()));
            if (a.ndim() != 2)
                throw ValueError("analyze: frame " + std::to_string(out.size()) + " has shape " +
                                 shape_text(a) + ": expected H x W");
            out.push_back(image_of(a));
        }
        return out;
    }
    const auto a = float_array(frames, "analyze");
    if (a.ndim() == 2) return {image_of(a)};
    if (a.ndim() != 3)
        throw ValueError("analyze: array of shape " + shape_text(a) +
                         ": expected H x W (one frame) or N x H x W (frames)");
    const size_t plane = size_t(a.shape(1)) * size_t(a.shape(2));
    for (py::ssize_t i = 0; i < a.shape(0); ++i) {
        analysis::Image im;
        im.height = int(a.shape(1)), im.width = int(a.shape(2));
        im.data.assign(a.data() + i * plane, a.data() + (i + 1) * plane);
        out.push_back(std::move(im));
    }
    return out;
}

py::object analyze(const py::handle& frames, const py::object& scene, const py::object& overrides,
                   bool structure) {
    analysis::AnalyzeOptions o;
    o.input = "array";
    o.structure = structure;
    o.sets = override_strings(overrides);
    if (py::isinstance<SceneObject>(scene)) {
        const auto& s = scene.cast<const SceneObject&>();
        if (s.scene().path == "<string>")
            throw ValueError(
                "analyze: scene= a scene loaded from TOML text: give its file name "
                "(the analysis reloads the scene)");
        o.scene = s.scene().path;
        o.sets.insert(o.sets.begin(), s.overrides().begin(), s.overrides().end());
    } else if (!scene.is_none()) {
        o.scene = scene.cast<std::string>();
    }
    std::vector<analysis::Image> images = frames_of(frames);
    const auto theory = scenes::closed_form(o.scene, o.sets);
    std::string json;
    {
        py::gil_scoped_release release;
        json = analysis::to_json(
            analysis::analyze_frames(std::move(images), o, "array", true, 32, 0, theory.get()));
    }
    return py::module_::import("json").attr("loads")(json);
}

/// The keys `impulse preview --expose` would give sliders (scenes/exposed.h: the same values and
/// ranges), each as a dict {key, value, lo, hi, step, integer}.
py::list exposed_keys(const std::string& source, const std::vector<std::string>& specs) {
    if (is_toml_text(source))
        throw ValueError("exposed_keys: TOML text: expected a scene file or a built-in name (the "
                         "keys are read from the file and its includes)");
    py::list out;
    for (const scenes::Exposed& e :
         scenes::exposed_keys(scenes::resolve_scene(source), specs)) {
        py::dict d;
        d["key"] = e.key, d["value"] = e.value, d["lo"] = e.lo, d["hi"] = e.hi;
        d["step"] = e.step, d["integer"] = e.integer;
        out.append(d);
    }
    return out;
}

/// Grid placement keywords shared by set_flow and set_orientation.
template <class Grid>
void place(Grid& g, const py::array& a, double spacing, std::pair<double, double> origin) {
    g.height = int(a.shape(0)), g.width = int(a.shape(1));
    if (!(spacing > 0.0) || !std::isfinite(spacing))
        throw ValueError("spacing " + std::to_string(spacing) +
                         ": expected texture units per "
                         "array pixel, > 0");
    g.spacing = spacing, g.origin_x = origin.first, g.origin_y = origin.second;
}

void set_flow(SceneObject& s, size_t layer, const py::handle& velocity, double spacing,
              std::pair<double, double> origin, double gain) {
    const auto a = float_array(velocity, "set_flow");
    if (a.ndim() != 3 || a.shape(2) != 2 || a.shape(0) < 1 || a.shape(1) < 1)
        throw ValueError("set_flow: array of shape " + shape_text(a) +
                         ": expected H x W x 2 (vx, vy in texture units per second)");
    sim::VectorGrid g;
    place(g, a, spacing, origin);
    for (py::ssize_t i = 0; i < a.shape(0) * a.shape(1); ++i)
        g.vx.push_back(a.data()[2 * i]), g.vy.push_back(a.data()[2 * i + 1]);
    s.set_flow(layer, std::move(g), gain);
}

void set_orientation(SceneObject& s, size_t layer, const py::handle& field, double spacing,
                     std::pair<double, double> origin, double jitter) {
    const auto a = float_array(field, "set_orientation");
    const bool ok = (a.ndim() == 2 || (a.ndim() == 3 && a.shape(2) == 2)) && a.size() > 0;
    if (!ok)
        throw ValueError("set_orientation: array of shape " + shape_text(a) +
                         ": expected H x W (angles in radians) or H x W x 2 (directions x, y)");
    sim::OrientationGrid g;
    place(g, a, spacing, origin);
    g.channels = a.ndim() == 2 ? 1 : 2;
    g.values.assign(a.data(), a.data() + a.size());
    s.set_orientation(layer, std::move(g), jitter);
}

/// Python exception classes for impulse's typed errors: each also derives from the matching
/// built-in class (SceneError and ValueError from ValueError, IoError from OSError). Translators
/// run newest first, so the base class, registered first, catches only what the others do not.
void register_errors(py::module_& m) {
    const py::handle base = py::register_exception<Error>(m, "Error", PyExc_Exception);
    const py::handle value = PyExc_ValueError, os = PyExc_OSError;
    py::register_exception<SceneError>(m, "SceneError", py::make_tuple(base, value));
    py::register_exception<ValueError>(m, "ValueError", py::make_tuple(base, value));
    py::register_exception<IoError>(m, "IoError", py::make_tuple(base, os));
    py::register_exception<BudgetError>(m, "BudgetError", base);
}

}  // namespace
}  // namespace impulse::python

PYBIND11_MODULE(impulse, m) {
    using namespace impulse::python;
    namespace scenes = impulse::scenes;
    m.doc() =
        "impulse: animated procedural textures from sparse convolution noise (Lewis 1986), "
        "rendered to numpy arrays";
    register_errors(m);
    m.def("_set_builtin_scene_dir", &scenes::set_builtin_scene_dir, py::arg("dir"),
          "Where built-in scene names are looked up (the installed package's impulse/scenes).");

    py::class_<SceneObject, std::shared_ptr<SceneObject>>(m, "Scene")
        .def_property_readonly("width", [](const SceneObject& s) { return s.scene().output.width; })
        .def_property_readonly("height",
                               [](const SceneObject& s) { return s.scene().output.height; })
        .def_property_readonly("frames",
                               [](const SceneObject& s) { return s.scene().output.frames; })
        .def_property_readonly("fps", [](const SceneObject& s) { return s.scene().output.fps; })
        .def_property_readonly("path", [](const SceneObject& s) { return s.scene().path; })
        .def_property_readonly("hash", [](const SceneObject& s) { return s.scene().hash; })
        .def_property_readonly("seed", [](const SceneObject& s) { return s.scene().seed; })
        .def_property_readonly("layers",
                               [](const SceneObject& s) { return s.scene().layers.size(); })
        .def_property_readonly("warnings", [](const SceneObject& s) { return s.scene().warnings; })
        .def("__repr__",
             [](const SceneObject& s) {
                 const auto& o = s.scene().output;
                 return "<impulse.Scene " + s.scene().path + " " + std::to_string(o.width) + "x" +
                        std::to_string(o.height) + ", " + std::to_string(o.frames) + " frames at " +
                        py::repr(py::float_(o.fps)).cast<std::string>() + " fps>";
             })
        .def(
            "frame_time", [](const SceneObject& s, int64_t f) { return s.scene().frame_time(f); },
            py::arg("frame"), "Time of frame `frame` in seconds.")
        .def("render", &render, py::arg("frame") = 0,
             "The float field of a frame as a float32 H x W array (the values `impulse render` "
             "writes to EXR, bit for bit). The GIL is released while it renders.")
        .def("render_channels", &render_channels, py::arg("frame"), py::arg("channels"),
             "The channels named in `channels` (value, dx, dy, normal, motion; docs/channels.md) "
             "of a frame as a dict of float32 H x W arrays keyed as `impulse render --channels` "
             "names them in an EXR (value, layer0.value, dx, dy, N.X, forward.u ...).")
        .def("render_rgb", &render_rgb, py::arg("frame") = 0,
             "Display colour of a frame as a float32 H x W x 3 array in [0, 1]: the scene's "
             "value mapping and shading (what PNG and video output show).")
        .def(
            "mapping",
            [](SceneObject& s) {
                const auto range = s.mapping();
                return std::make_pair(range.lo, range.hi);
            },
            "The (lo, hi) field values shown as black and white.")
        .def("theory", &theory, py::arg("frame") = 0,
             "Closed-form statistics at a frame's time: a dict with mean, variance (Campbell's "
             "theorem) and spectrum {frequency (cycles per pixel), power} radially averaged, or "
             "None with spectrum_note saying why.")
        .def("set_flow", &set_flow, py::arg("layer"), py::arg("velocity"), py::arg("spacing") = 1.0,
             py::arg("origin") = std::make_pair(0.0, 0.0), py::arg("gain") = 1.0,
             "Carry layer `layer`'s impulses in the flow sampled by `velocity` (H x W x 2, vx and "
             "vy in texture units per second; pixel (i, j) at origin + (i + 0.5, j + 0.5) "
             "spacing), bilinear, clamped at the edges.")
        .def("set_orientation", &set_orientation, py::arg("layer"), py::arg("field"),
             py::arg("spacing") = 1.0, py::arg("origin") = std::make_pair(0.0, 0.0),
             py::arg("jitter") = 0.0,
             "Turn layer `layer`'s kernels along `field`: H x W angles in radians or H x W x 2 "
             "directions, placed as set_flow's array.");

    m.def("load_scene", &load, py::arg("source"), py::arg("overrides") = py::none(),
          py::arg("size") = py::none(),
          "Load a scene: `source` is a TOML file, a built-in scene's name, or TOML text (a string "
          "with a newline or '='). `overrides` is a dict {\"layer.0.kernel.radius\": 8} or a list "
          "of \"key=value\" (the CLI's --set); `size` = (width, height) renders the same view at "
          "another resolution (the CLI's --size).");
    m.def("analyze", &analyze, py::arg("frames"), py::arg("scene") = py::none(),
          py::arg("overrides") = py::none(), py::arg("structure") = false,
          "Analyse an H x W array, an N x H x W array or a list of H x W arrays (float32 or "
          "float64): moments, spectrum, autocovariance, stationarity; with `scene` (a file, a "
          "built-in name or a Scene loaded from a file) compared with its theory. Returns the "
          "dict of `impulse analyze --json`.");
    m.def("exposed_keys", &exposed_keys, py::arg("source"), py::arg("specs"),
          "The numeric keys `impulse preview --expose` gives sliders: `specs` as --expose takes "
          "them (\"layer.0.kernel.radius\" or \"layer.0.density=4:32\"), looked up in the scene "
          "file (a file or a built-in name) and its includes; a list of dicts {key, value, lo, "
          "hi, step, integer} with the preview's ranges (0 to twice the value unless given).");
    m.def("scenes_dir", &scenes::builtin_scene_dir, "Directory of the built-in scenes.");
}
