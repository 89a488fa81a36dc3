// SPDX-License-Identifier: Apache-2.0
#pragma once
// impulse::sim — the shaped Poisson point process as a particle system (Lewis 1986 §3.1):
// consistent cell-seeded births in space and time, flows, integration, the Jacobian
// compensation and orientation, and the set of live impulses at any frame.
// Knows nothing of rendering, cameras or the command line.

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "numeric/box.h"
#include "numeric/keyframed.h"

namespace impulse::sim {

// Time-varying scalars and texture-space boxes come from the base library.
using numeric::Box;
using numeric::Ease;
using numeric::Keyframed;
using numeric::Region;

// ---------------------------------------------------------------------------------------------
// Amplitudes and temporal envelopes

/// The amplitude law of the impulses. Normal, uniform on [-1, 1] and sign (+-1) are zero-mean;
/// exponential (rate 1, a = -ln u) is positive, for fields that are a non-negative quantity
/// (dye, heat): the field's mean is then lambda E[a] int h, not 0 (Campbell's theorem).
enum class Amplitude { Normal, Uniform, Sign, Exponential };
inline constexpr std::array<std::string_view, 4> kAmplitudeNames = {"normal", "uniform", "sign",
                                                                    "exponential"};
std::optional<Amplitude> amplitude_from_string(std::string_view name);
/// E[a]: 0 for normal, uniform and sign; 1 for exponential.
double amplitude_mean(Amplitude a);
/// E[a^2]: normal 1, uniform on [-1, 1] 1/3, sign 1, exponential 2.
double amplitude_second_moment(Amplitude a);
/// E[a^4]: normal 3, uniform 1/5, sign 1, exponential 24.
double amplitude_fourth_moment(Amplitude a);

/// Temporal envelope w(age) of a particle living T seconds: the time half of a space-time kernel.
enum class Envelope { Hann, Box };
inline constexpr std::array<std::string_view, 2> kEnvelopeNames = {"hann", "box"};
std::optional<Envelope> envelope_from_string(std::string_view name);
/// w(age): hann sin^2(pi age / T), box 1, both 0 outside [0, T).
double envelope_weight(Envelope e, double age_s, double lifetime_s);
/// int_0^T w^2 dt: hann 3T/8, box T.
double envelope_sq_integral(Envelope e, double lifetime_s);
/// int_0^T w dt: hann T/2, box T.
double envelope_integral(Envelope e, double lifetime_s);
/// int_0^T w^4 dt: hann 35T/128, box T (the impulse population's fourth cumulant).
double envelope_fourth_integral(Envelope e, double lifetime_s);

// ---------------------------------------------------------------------------------------------
// Flows

/// A velocity field v(x, t) in texture units per second with its divergence and vorticity
/// (curl, counter-clockwise positive). Implementations accumulate (+=) into the outputs so
/// a sum of flows is a loop over its terms. Evaluation is deterministic and thread-safe once
/// `prepare` has run.
class Flow {
public:
    virtual ~Flow() = default;
    /// Add v, div v and curl v at n points (x[i], y[i]) at time t. `div` and `curl` may be
    /// null when the caller does not need them (the flow then skips their work); v is the same
    /// either way, bit for bit.
    virtual void add(double t_s, size_t n, const double* x, const double* y, double* vx,
                     double* vy, double* div, double* curl) const = 0;
    /// True when div v = 0 everywhere and at all times, so `add` would only add zeros to `div`
    /// (the simulator then does not integrate ln J: it stays exactly 0).
    virtual bool divergence_free() const { return false; }
    /// Upper bound of |v| over `region` and all time.
    virtual double max_speed(const Box& region) const = 0;
    /// Bounds {vx_min, vx_max, vy_min, vy_max} over `region` and all time (default: +-max_speed);
    /// the birth region extends upstream only as far as these allow (design.md §3).
    virtual std::array<double, 4> velocity_bounds(const Box& region) const {
        const double s = max_speed(region);
        return {-s, s, -s, s};
    }
    /// Called (single-threaded) before a frame is integrated over `region`; lets a flow build
    /// caches. Default: nothing.
    virtual void prepare(const Box& region) { (void)region; }
    /// Called (single-threaded) before a frame is integrated with the times of every step it
    /// may evaluate, [t0_s, t1_s]: lets a flow sampled in time load the frames it needs and drop
    /// the others. Default: nothing.
    virtual void prepare_span(double t0_s, double t1_s) { (void)t0_s, (void)t1_s; }
    /// Bytes prepare(region) may hold at most, for the memory budget (limits.max_memory_mib):
    /// checked at load, before any cache is built. Default: none.
    virtual double cache_bytes(const Box& region) const {
        (void)region;
        return 0.0;
    }
};

/// Sum of flow primitives (scene `[[layer.flow]]` list).
class FlowSum final : public Flow {
public:
    void push(std::unique_ptr<Flow> f) { m_terms.push_back(std::move(f)); }
    bool empty() const { return m_terms.empty(); }
    void add(double t_s, size_t n, const double* x, const double* y, double* vx, double* vy,
             double* div, double* curl) const override;
    bool divergence_free() const override;
    double max_speed(const Box& region) const override;
    std::array<double, 4> velocity_bounds(const Box& region) const override;
    void prepare(const Box& region) override;
    void prepare_span(double t0_s, double t1_s) override;
    double cache_bytes(const Box& region) const override;

private:
    std::vector<std::unique_ptr<Flow>> m_terms;
};

/// Uniform wind (vx, vy).
std::unique_ptr<Flow> make_uniform_flow(Keyframed vx, Keyframed vy);
/// Shear: velocity `rate * (p - c) . n_perp` along direction `angle`, where n_perp is the unit
/// normal to that direction; curl = -rate. Every parameter may vary in time.
std::unique_ptr<Flow> make_shear_flow(Keyframed rate, Keyframed cx, Keyframed cy,
                                      Keyframed angle_rad);
enum class VortexModel { LambOseen, Rankine };
inline constexpr std::array<std::string_view, 2> kVortexModelNames = {"lamb-oseen", "rankine"};
std::optional<VortexModel> vortex_model_from_string(std::string_view name);
/// Vortex of circulation `circulation` (units^2/s, positive counter-clockwise) and core radius
/// (> 0 at every key).
std::unique_ptr<Flow> make_vortex_flow(VortexModel model, Keyframed cx, Keyframed cy,
                                       Keyframed circulation, Keyframed core_radius);
/// Source (rate > 0) or sink (rate < 0): v = rate (x - c) g(r), g = exp(-r^2 / radius^2)
/// (radius = 0: g = 1, a uniform divergence 2 rate). div v = rate g (2 - 2 r^2 / radius^2).
/// A keyframed radius must be > 0 at every key (0 is a different field, not a limit of it).
std::unique_ptr<Flow> make_source_flow(Keyframed cx, Keyframed cy, Keyframed rate,
                                       Keyframed radius);
/// Divergence-free curl noise: v = (d psi/dy, -d psi/dx) of a sparse-convolution potential psi
/// with compact kernel (1 - r^2/s^2)^3 of radius `scale`; consistent (counter-based per cell)
/// and periodic when `period` is given (a multiple of the cell size is chosen). `speed` is the
/// RMS speed.
/// Throws ValueError for a scale outside [kMinCurlScale, kMaxCurlScale]; prepare() throws
/// ValueError when the lattice over its region would exceed 1e8 nodes.
std::unique_ptr<Flow> make_curl_noise_flow(uint64_t seed, double scale, Keyframed speed,
                                           std::optional<std::array<double, 2>> period);
inline constexpr double kMinCurlScale = 1e-3, kMaxCurlScale = 1e9;
/// A field sampled from a 2-channel grid (vx, vy in units per second), bilinear, clamped at the
/// edges; grid pixel (i, j) sits at texture point origin + (i + 0.5, j + 0.5) * spacing.
struct VectorGrid {
    int width = 0, height = 0;
    std::vector<float> vx, vy;
    double origin_x = 0, origin_y = 0, spacing = 1.0;
};
/// Throws ValueError for a malformed grid or a velocity that is not finite (naming its pixel).
std::unique_ptr<Flow> make_grid_flow(VectorGrid grid, Keyframed gain);

// ---------------------------------------------------------------------------------------------
// Velocity sequences (sim/sequence.cpp): a sampled field that varies in time

/// How a sequence is read between its frames: linear over two frames, or Catmull-Rom cubic
/// over four.
enum class TimeInterpolation { Linear, Cubic };
inline constexpr std::array<std::string_view, 2> kTimeInterpolationNames = {"linear", "cubic"};
/// The field outside the sampled domain: zero, the value at the nearest point of the domain
/// (clamped coordinates, interpolated along the edge), or the nearest sample's value.
enum class Outside { Zero, Clamp, Nearest };
inline constexpr std::array<std::string_view, 3> kOutsideNames = {"zero", "clamp", "nearest"};

/// One frame of a velocity sequence on a plane: sample (i, j) at grid index (i, j), velocities
/// in texture units per second, row-major (vx[j * width + i]).
struct PlaneFrame {
    int width = 0, height = 0;
    std::vector<float> vx, vy;
};

/// Where a sequence's frames come from (scenes/ reads them from files). Thread-safe.
class FrameSource {
public:
    virtual ~FrameSource() = default;
    /// Frame n of the sequence. Throws Error (ValueError, IoError) with a one-line message.
    virtual PlaneFrame load(int64_t n) const = 0;
};

/// A velocity sequence laid on texture space.
struct SequenceConfig {
    std::shared_ptr<const FrameSource> source;
    int64_t first = 0, last = 0;  ///< the sequence's frame numbers, first <= last, none missing
    int width = 1, height = 1;    ///< every frame's grid size
    /// Scene time to sequence frame: u(t) = start + rate t (frames of the sequence a second);
    /// u is held to [first, last] (the first frame before it, the last after).
    double start = 0.0, rate = 24.0;
    /// Texture point to grid index: (i, j) = A (x, y) + b, A = {a00, a01, a10, a11} invertible.
    std::array<double, 4> to_index{1.0, 0.0, 0.0, 1.0};
    std::array<double, 2> index_offset{0.0, 0.0};
    TimeInterpolation time = TimeInterpolation::Linear;
    Outside outside = Outside::Zero;
    double max_sample_speed = 0.0;  ///< max |v| over every frame's samples (the speed bound)
    double span_s = 0.0;  ///< the layer's lifetime: the time span prepare_span covers, less a step
    bool read_ahead = true;  ///< load the frame after a span in the background
};
/// The sampled flow: bilinear in space, linear or cubic in time, with the divergence and curl
/// of that interpolant (exact: the d ln J/dt = div v of design.md §1 is the interpolated field's
/// own). Holds only the frames its last prepare_span needs (plus the one read ahead); a frame
/// asked for outside them is loaded on demand. Throws ValueError for a malformed config.
std::unique_ptr<Flow> make_sequence_flow(SequenceConfig config);
/// The largest |div v| of the bilinear interpolant of `frame` with texture-to-index map
/// `to_index` over the grid (exact: on each cell div v is affine in the cell's coordinates, so
/// its extremes sit on the cell's corners).
double max_interpolated_divergence(const PlaneFrame& frame, const std::array<double, 4>& to_index);

// ---------------------------------------------------------------------------------------------
// Orientation fields (sim/orientation.cpp)

/// A direction field theta(x, t) in radians, counter-clockwise from +x, that rotates each
/// impulse's kernel; evaluated at the particle's current position at the frame time ("wind-blown
/// clouds or terrain ridges ... emulated by rotating the kernel as a function of position",
/// Lewis 1986 §3.1). Deterministic and thread-safe.
class OrientationField {
public:
    virtual ~OrientationField() = default;
    /// theta at the n points (x[i], y[i]) at time t_s, into theta[i].
    virtual void angles(double t_s, size_t n, const double* x, const double* y,
                        float* theta) const = 0;
};
/// theta = angle(t) everywhere.
std::shared_ptr<OrientationField> make_constant_orientation(Keyframed angle_rad);
/// theta = atan2(y - cy, x - cx): kernels point away from the centre (0 at the centre itself).
std::shared_ptr<OrientationField> make_radial_orientation(Keyframed cx, Keyframed cy);
/// The radial angle + pi/2 (counter-clockwise around the centre), or - pi/2 when `clockwise`.
std::shared_ptr<OrientationField> make_circular_orientation(Keyframed cx, Keyframed cy,
                                                            bool clockwise);
/// Tangent of a polyline (>= 2 points, consecutive points distinct): the direction of the
/// nearest segment; with `smooth` > 0 (texture units) the segment directions are averaged as
/// doubled-angle vectors with weights exp(-(d_i^2 - d_min^2) / (2 smooth^2)), d_i the distance
/// to segment i, so the field turns smoothly at the vertices. `smooth` may vary in time.
std::shared_ptr<OrientationField> make_polyline_orientation(std::vector<std::array<double, 2>> points,
                                                            Keyframed smooth);
/// Tangent of a family of sine curves. In coordinates (u, w) along direction `angle_rad`
/// through `origin` (u = (p - origin) . (cos angle, sin angle)), the curve is
/// w = amplitude sin(2 pi u / wavelength + phase) and every point takes the tangent of the copy
/// through it (shifted across): theta = angle + atan(2 pi amplitude / wavelength
/// cos(2 pi u / wavelength + phase)). wavelength > 0 at every key; amplitude, wavelength, phase
/// and angle may vary in time.
std::shared_ptr<OrientationField> make_sine_orientation(Keyframed amplitude, Keyframed wavelength,
                                                        Keyframed phase, Keyframed angle_rad,
                                                        double origin_x, double origin_y);
/// A sampled field: channels = 1, an angle in radians; channels = 2, a direction (x, y).
/// Interpolated bilinearly as unit vectors (angles) or as vectors (directions), clamped at the
/// edges; grid pixel (i, j) sits at texture point origin + (i + 0.5, j + 0.5) * spacing.
struct OrientationGrid {
    int width = 0, height = 0, channels = 1;
    std::vector<float> values;  ///< width * height * channels, row-major, interleaved
    double origin_x = 0, origin_y = 0, spacing = 1.0;
};
/// Throws ValueError for a malformed grid or a value that is not finite (naming its pixel).
std::shared_ptr<OrientationField> make_grid_orientation(OrientationGrid grid);

// ---------------------------------------------------------------------------------------------
// Birth regions (sim/region.cpp)

/// A planar shape as a signed distance d(x, y): negative inside, positive outside, zero on the
/// boundary. Exact (|d| is the Euclidean distance to the boundary) for the primitives; the
/// combinations take min / max of their parts, which is exact outside a union and a lower bound
/// of the distance otherwise (exact at the boundary itself). Deterministic and thread-safe.
class Shape {
public:
    virtual ~Shape() = default;
    virtual double distance(double x, double y) const = 0;
    /// The axis-aligned box holding the inside (d <= 0).
    virtual Box bounds() const = 0;
};
/// Disc of `radius` > 0 round (cx, cy).
std::shared_ptr<const Shape> make_circle_shape(double cx, double cy, double radius);
/// Rectangle of half-sizes (hx, hy) > 0 centred on (cx, cy), turned by `angle_rad`
/// counter-clockwise, with corners rounded to `corner` in [0, min(hx, hy)] (0: sharp).
std::shared_ptr<const Shape> make_box_shape(double cx, double cy, double hx, double hy,
                                            double angle_rad, double corner);
/// Ellipse of semi-axes (a, b) > 0 centred on (cx, cy), the a axis turned by `angle_rad`. The
/// distance is the exact one (closest point found by bisection, Eberly 2013).
std::shared_ptr<const Shape> make_ellipse_shape(double cx, double cy, double a, double b,
                                                double angle_rad);
/// Capsule: the points within `radius` > 0 of the segment (ax, ay)-(bx, by) (a disc if a = b).
std::shared_ptr<const Shape> make_capsule_shape(double ax, double ay, double bx, double by,
                                                double radius);
/// Which points a self-intersecting polygon holds: even-odd (a point is inside when a ray from
/// it crosses the boundary an odd number of times) or nonzero (when the boundary winds round it
/// a nonzero number of times: overlapping loops are filled). Equal for simple polygons.
enum class FillRule { EvenOdd, NonZero };
inline constexpr std::array<std::string_view, 2> kFillRuleNames = {"evenodd", "nonzero"};
/// Closed polygon through `points` (>= 3, not all on one line; the last joins the first).
/// Throws ValueError for a degenerate polygon.
std::shared_ptr<const Shape> make_polygon_shape(std::vector<std::array<double, 2>> points,
                                                FillRule rule);
/// Union (min), intersection (max) or the first part minus all the others (max(d0, -d1, ...)).
enum class ShapeOp { Union, Intersection, Subtract };
inline constexpr std::array<std::string_view, 3> kShapeOpNames = {"union", "intersection",
                                                                  "subtract"};
std::shared_ptr<const Shape> make_combined_shape(ShapeOp op,
                                                 std::vector<std::shared_ptr<const Shape>> parts);

/// Where a layer's impulses may be born (Lewis 1986 §3.1: points "restricted to an area of the
/// plane"): an acceptance probability p(x, y) in [0, 1] at the birth position. The simulator
/// thins births with it (a birth is kept iff a uniform drawn from its identity is <= p), so the
/// kept impulses are a Poisson process of intensity lambda p(x) and, where p varies slowly on
/// the kernel's scale, the field's local variance is p(x) times the layer's. Deterministic and
/// thread-safe.
class BirthRegion {
public:
    virtual ~BirthRegion() = default;
    /// p(x, y) in [0, 1].
    virtual double acceptance(double x, double y) const = 0;
    /// A box outside which p = 0, or nullopt when p may be positive anywhere (an inverted
    /// region); the simulator does not generate seeding cells outside it.
    virtual std::optional<Box> support() const = 0;
};
/// A shape with a soft edge: p = 1 - smoothstep((d + feather/2) / feather), so p falls from 1
/// at d = -feather/2 to 0 at d = feather/2 (1/2 on the boundary); feather = 0 is a hard edge
/// (p = 1 for d <= 0). `invert`: 1 - p (births outside the shape).
std::shared_ptr<const BirthRegion> make_shape_region(std::shared_ptr<const Shape> shape,
                                                     double feather, bool invert);
/// A sampled mask: grid pixel (i, j) sits at texture point origin + (i + 0.5, j + 0.5) * spacing
/// (as OrientationGrid); p is the bilinear interpolation of the values, which must lie in
/// [0, 1], held at the edges (clamped coordinates). `invert`: 1 - p.
struct MaskGrid {
    int width = 0, height = 0;
    std::vector<float> values;  ///< width * height, row-major, in [0, 1]
    double origin_x = 0, origin_y = 0, spacing = 1.0;
};
/// Throws ValueError for a malformed grid or values outside [0, 1].
std::shared_ptr<const BirthRegion> make_mask_region(MaskGrid grid, bool invert);
/// The same acceptance as `region` without a support: the simulator then generates every
/// seeding cell and thins each birth — the reference path for the culling (same impulses, bit
/// for bit; tests and benchmarks compare the two).
std::shared_ptr<const BirthRegion> without_support(std::shared_ptr<const BirthRegion> region);

// ---------------------------------------------------------------------------------------------
// The point process of one layer

enum class Integrator { RK2, RK4 };
inline constexpr std::array<std::string_view, 2> kIntegratorNames = {"rk2", "rk4"};
std::optional<Integrator> integrator_from_string(std::string_view name);

/// How a particle's kernel rotation theta evolves. `Fixed`: 0 (the kernel's own orientation);
/// `Random`: an angle uniform in [0, 2 pi) drawn at birth, kept for life; `Flow`: the direction
/// of v at the particle at the frame time; `Vorticity`: integrated along the path from 0 at
/// birth, d theta/dt = omega/2 (design.md §1). `Field`: from ProcessConfig::orientation_field
/// (set by a table in scene files, hence not among the names below).
enum class OrientationMode { Fixed, Random, Flow, Vorticity, Field };
inline constexpr std::array<std::string_view, 4> kOrientationModeNames = {"fixed", "random", "flow",
                                                                          "vorticity"};
std::optional<OrientationMode> orientation_mode_from_string(std::string_view name);

/// Everything that defines a layer's impulses. Validated by the scene loader.
struct ProcessConfig {
    uint64_t seed = 1;           ///< user seed
    uint32_t layer = 0;          ///< layer index (part of the generator key)
    double intensity = 0.02;     ///< lambda: expected live impulses per unit area, > 0
    Amplitude amplitude = Amplitude::Normal;
    double cell_size = 16.0;     ///< spatial cell edge used for seeding, > 0
    /// Periodic domain (tileable output, Lewis 1986 §3.2): cell keys wrap with this period.
    std::optional<std::array<double, 2>> period;

    double lifetime_s = 0.0;     ///< 0: a still process (no births in time, no motion)
    Envelope envelope = Envelope::Hann;
    double loop_s = 0.0;         ///< > 0: births periodic in time with this period
    Integrator integrator = Integrator::RK2;
    int substeps = 2;            ///< integration steps per frame, >= 1
    bool jacobian = true;        ///< scale amplitudes by sqrt(J) (design.md §1)
    OrientationMode orientation = OrientationMode::Fixed;
    double max_travel = 4096.0;  ///< refuse flows that carry particles further in one lifetime
    /// OrientationMode::Field: theta(x, t) at each particle's position at the frame time.
    std::shared_ptr<const OrientationField> orientation_field;
    /// OrientationMode::Field: plus a random angle per particle, uniform in [-jitter, jitter)
    /// radians: the uniform is drawn at birth (from the particle's identity), the spread
    /// jitter(t) is evaluated at the frame time (loop-wrapped like the flow).
    Keyframed orientation_jitter = 0.0;
    /// A time-varying birth rate by thinning (Lewis-Shedler): births are generated at the
    /// maximum rate `intensity` and one born at time t_b (loop-reduced in a looped process) is
    /// kept iff a uniform of its own identity is below density_scale(t_b), a value in [0, 1].
    /// The live intensity at t is then (intensity / T) int_0^T density_scale(t - a) da, and the
    /// variance carries density_scale(t - a) w(a)^2 under the integral (Campbell's theorem).
    /// Empty: a constant rate (no thinning; the impulses of a constant-rate process).
    /// Must be a pure function of t; only for processes with lifetime_s > 0.
    std::function<double(double)> density_scale;
    /// Births confined to a region (null: everywhere): a birth at (x, y) is kept iff a uniform
    /// drawn from its identity (seed, layer, cell, index, on a stream of its own) is <= p(x, y)
    /// at its birth position; then it moves with the flow as usual.
    std::shared_ptr<const BirthRegion> region;
};

// ---------------------------------------------------------------------------------------------
// A layer's field as a stream function (sim/stream.cpp)

/// A still process's field used as a stream function (sim/stream.cpp): the velocity of a layer
/// that flows along another layer's level lines. psi(x) = gain sum_k a_k h(x - x_k; theta_k)
/// with theta_k = the impulse's random angle for OrientationMode::Random, else 0.
struct StreamFunction {
    ProcessConfig process;  ///< a still process (lifetime 0) whose cell_size >= radius
    double gain = 1.0;      ///< != 0: its sign sets the sense of rotation, its size cancels
    double radius = 0.0;    ///< support radius of h, > 0
    /// h at offset (dx, dy) from an impulse rotated by theta radians; 0 beyond `radius`.
    std::function<double(double dx, double dy, double theta)> kernel;
    /// The kernel's semivariogram (1/2) int (h(x) - h(x + tau))^2 d^2x = C(0) - C(tau) at
    /// tau = (tx, ty), C the kernel's autocorrelation, averaged over the impulses' rotations (the
    /// field's covariance is lambda E[a^2] C). Differences of C set the gradient's variance, and
    /// computed this way they keep their relative accuracy at small lags.
    std::function<double(double tx, double ty)> semivariogram;
};
/// v = speed(t) sgn(gain) (d psi/dy, -d psi/dx) / sqrt(E|grad psi|^2): divergence-free, with
/// RMS speed `speed`, curl v = -lap psi scaled alike. psi is sampled at the nodes of a fixed
/// lattice (8 per seeding cell, whole multiples of the spacing) and interpolated with Catmull-Rom
/// bicubics, as the curl-noise flow does, so the flow is a pure function of (x, t) and exactly
/// divergence-free; E|grad psi|^2 is that of the interpolant, from the semivariogram.
std::unique_ptr<Flow> make_stream_flow(StreamFunction psi, Keyframed speed);
/// E|grad psi_I|^2 / gain^2 of make_stream_flow's interpolated stream function, averaged over
/// position (Campbell's theorem on the lattice; for tests and normalisation).
double stream_gradient_variance(const StreamFunction& psi);

/// Frame timing: frame f is at time (start_frame + f) / fps seconds.
struct Timing {
    double fps = 30.0;
    int64_t start_frame = 0;
};

/// The live impulses of a layer at one frame, in canonical order (by time cell, spatial cell,
/// index), structure of arrays. weight = a * w(age) * sqrt(J); theta = rotation added to the
/// kernel's own orientation (radians). scale: empty (every kernel at its own size), or one
/// factor per impulse by which the renderer scales its kernel (a scene's scale field; the
/// simulator never sets it, see render::accumulate).
struct Impulses {
    std::vector<double> x, y;
    std::vector<float> weight, theta;
    std::vector<float> scale;
    size_t size() const { return x.size(); }
    void clear();
};

/// Impulses of one seeding cell before any motion (for consistency tests).
struct CellImpulses {
    std::vector<double> x, y, birth_s;
    std::vector<float> amplitude, theta0;
};
/// Impulses born in spatial cell (cx, cy) and time cell ct (ct = 0 for a still process) of a
/// process; a pure function of (config, cx, cy, ct).
void cell_impulses(const ProcessConfig& config, int64_t cx, int64_t cy, int64_t ct,
                   CellImpulses& out);

/// Expected number of impulses generated for `region` (before culling): the budget estimate.
double expected_impulses(const ProcessConfig& config, const Region& region);

/// A camera shutter for motion blur (docs/motion_blur.md): open over [t + open_s, t + close_s]
/// around the frame time t. Each live impulse is drawn as n copies at the centres of n equal
/// strata of that interval, weight 1/n each, n the smallest power of two (at most max_samples)
/// with the impulse's travel over the shutter / n <= max_step: an impulse that barely moves is
/// one copy.
struct Shutter {
    double open_s = 0.0, close_s = 0.0;  ///< offsets from the frame time, seconds, open <= close
    double max_step = 1.0;               ///< largest travel between copies, texture units, > 0
    int max_samples = 64;                ///< a power of two >= 1
    /// False for a shutter of zero length (an instant: the frame as without a shutter).
    bool open() const { return close_s > open_s; }
};

/// Produces the live impulses of one layer at any frame. Sequential calls (frame f then f+1)
/// reuse the previous state and step it; any other call integrates from birth. Both paths do the
/// same floating-point operations per particle, so results are bit-identical (design.md §3).
class LayerSimulator {
public:
    /// `flow` may be null (no motion). Throws ValueError if the flow's speed bound times the
    /// lifetime exceeds config.max_travel.
    LayerSimulator(ProcessConfig config, std::shared_ptr<Flow> flow, Timing timing,
                   double support_radius);
    ~LayerSimulator();
    LayerSimulator(LayerSimulator&&) noexcept;

    /// Impulses whose support can touch `view` (texture-space boxes) at frame `frame`. Only the
    /// seeding cells whose birth region meets a box are generated. A still process (no lifetime)
    /// writes its impulses straight into `out`, pieces of rows of cells in parallel, each in its
    /// place of the canonical order (the same values and order as cell_impulses cell by cell).
    void impulses_at(int64_t frame, const Region& view, Impulses& out);
    /// The same, motion-blurred over `shutter`: each live impulse's copies along its path
    /// (docs/motion_blur.md). A closed shutter gives impulses_at's impulses, bit for bit.
    void impulses_at(int64_t frame, const Region& view, const Shutter& shutter, Impulses& out);
    /// The birth region used for `view`: expanded by support radius + travel bound.
    Box birth_region(const Box& view) const;
    /// The birth regions of every box of `view`.
    Region birth_region(const Region& view) const;
    /// Travel bound (max speed * lifetime) for `view`, in texture units.
    double travel_bound(const Box& view) const;
    /// Bytes the flow's caches may hold for `view` (Flow::cache_bytes over the region
    /// impulses_at prepares the flow for); 0 for a still process or no flow.
    double flow_cache_bytes(const Region& view) const;
    /// Flow integration steps the first frame of `view` takes: each impulse held for its birth
    /// region (expected_impulses) is integrated from its birth, on average lifetime / 2 of
    /// fps * substeps steps a second, plus one frame; 0 for a still process or no flow. (Later
    /// frames move each impulse by one frame: `substeps` steps.)
    double first_frame_steps(const Region& view) const;
    const ProcessConfig& config() const;
    /// Forget the cached state (the next call integrates from birth).
    void reset();

private:
    struct State;
    std::unique_ptr<State> m_state;
};

}  // namespace impulse::sim
