// The filters of nbhd_filter_plugin.hpp over nbhd's C API.
#include "nbhd_filter_plugin.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <utility>

namespace nbhd_meshlab {
namespace {

const char* const kThesis =
    "<i>Martin Skrodzki</i><br/><b>\"Neighborhood Computation of Point Set Surfaces\"</b><br/>";

const char* stage_name(nbhd_stage s) {
    switch (s) {
        case NBHD_STAGE_NEIGHBORS: return "neighbourhoods";
        case NBHD_STAGE_GEOMETRY: return "normals and curvatures";
        case NBHD_STAGE_STEP: return "smoothing step";
        case NBHD_STAGE_OUTPUTS: return "per-vertex outputs";
        case NBHD_STAGE_DONE: return "done";
    }
    return "?";
}

// The C callback nbhd calls: forwards to the std::function, which must not let an exception
// cross into nbhd; one thrown is kept, the run cancelled, and the exception rethrown later.
struct ProgressBridge {
    const NbhdFilterPlugin::ProgressCallback* callback = nullptr;
    std::exception_ptr error;

    static bool call(double fraction, nbhd_stage stage, void* user) {
        auto* self = static_cast<ProgressBridge*>(user);
        try {
            return (*self->callback)(fraction, stage_name(stage));
        } catch (...) {
            self->error = std::current_exception();
            return false;
        }
    }
};

RichParameter param(std::string name, std::string description, RichParameter::Type type,
                    double def, double min, double max, std::vector<std::string> choices = {}) {
    RichParameter p;
    p.name = std::move(name);
    p.description = std::move(description);
    p.type = type;
    p.default_value = def;
    p.min = min;
    p.max = max;
    p.choices = std::move(choices);
    p.value = def;
    return p;
}

using T = RichParameter::Type;

// Orientation choices, in this order.
const std::vector<std::string> kOrientations = {"none", "propagate", "away_from_centroid"};
const std::vector<std::string> kQualities = {"mean", "max_principal", "covariance_quotient",
                                             "principal_quotient", "max_covariance"};
const std::vector<std::string> kWeightings = {"sharp", "continuous"};
const std::vector<std::string> kFeatures = {"all", "Q", "K", "D"};

// Reads the parameters of a run, converting and checking what must be checked before nbhd
// sees a value (whole numbers, enum indices); nbhd checks the rest.
class Reader {
public:
    Reader(const RichParameterList& params, const std::string& filter)
        : params_(params), filter_(filter) {}

    double real(const char* name) const { return params_.get(name).value; }

    bool flag(const char* name) const {
        double v = real(name);
        if (v != 0 && v != 1) fail(NBHD_STATUS_INVALID_ARGUMENT, name, "must be 0 or 1", v);
        return v == 1;
    }

    std::size_t whole(const char* name, nbhd_status status = NBHD_STATUS_INVALID_ARGUMENT) const {
        double v = real(name);
        if (!(v >= 0) || v != std::floor(v) || v > double(std::numeric_limits<std::uint32_t>::max()))
            fail(status, name, "must be a whole number >= 0", v);
        return std::size_t(v);
    }

    std::size_t choice(const char* name) const {
        const RichParameter& p = params_.get(name);
        double v = p.value;
        if (!(v >= 0) || v != std::floor(v) || v >= double(p.choices.size()))
            fail(NBHD_STATUS_INVALID_ARGUMENT, name,
                 "must be a choice index below " + std::to_string(p.choices.size()), v);
        return std::size_t(v);
    }

    [[noreturn]] void fail(nbhd_status status, const char* name, const std::string& what, double v) const {
        char got[32];
        std::snprintf(got, sizeof got, "%g", v);
        throw nbhd_filter_error(status, filter_ + ": parameter '" + name + "' " + what + ", got " + got);
    }

private:
    const RichParameterList& params_;
    const std::string& filter_;
};

nbhd_units units(bool absolute) { return absolute ? NBHD_UNITS_ABSOLUTE : NBHD_UNITS_RELATIVE; }

}  // namespace

// ---- RichParameterList

void RichParameterList::add(RichParameter p) {
    if (has(p.name)) throw nbhd_filter_error(NBHD_STATUS_INVALID_ARGUMENT, "parameter '" + p.name + "' added twice");
    params_.push_back(std::move(p));
}

bool RichParameterList::has(const std::string& name) const {
    return std::any_of(params_.begin(), params_.end(), [&](const RichParameter& p) { return p.name == name; });
}

const RichParameter& RichParameterList::get(const std::string& name) const {
    for (const RichParameter& p : params_)
        if (p.name == name) return p;
    throw nbhd_filter_error(NBHD_STATUS_INVALID_ARGUMENT, "no parameter '" + name + "'");
}

void RichParameterList::set(const std::string& name, double value) {
    const_cast<RichParameter&>(get(name)).value = value;
}

void RichParameterList::setEnum(const std::string& name, const std::string& choice) {
    RichParameter& p = const_cast<RichParameter&>(get(name));
    auto it = std::find(p.choices.begin(), p.choices.end(), choice);
    if (p.type != T::Enum || it == p.choices.end())
        throw nbhd_filter_error(NBHD_STATUS_INVALID_ARGUMENT,
                                "parameter '" + name + "' has no choice '" + choice + "'");
    p.value = double(it - p.choices.begin());
}

// ---- the plugin

NbhdFilterPlugin::NbhdFilterPlugin()
    : types_{FP_COMPUTE_NORMALS, FP_COMPUTE_CURVATURES, FP_ISOTROPIC_SMOOTHING, FP_ANISOTROPIC_SMOOTHING} {}

std::string NbhdFilterPlugin::filterName(FilterId id) const {
    switch (id) {
        case FP_COMPUTE_NORMALS: return "Compute Normals (nbhd, eps-k neighbourhoods)";
        case FP_COMPUTE_CURVATURES: return "Compute Curvatures as Quality (nbhd, Weingarten map)";
        case FP_ISOTROPIC_SMOOTHING: return "Point Set Smoothing: Isotropic (nbhd)";
        case FP_ANISOTROPIC_SMOOTHING: return "Point Set Smoothing: Anisotropic Mean Curvature Flow (nbhd)";
    }
    throw nbhd_filter_error(NBHD_STATUS_INVALID_ARGUMENT, "unknown filter id " + std::to_string(int(id)));
}

std::string NbhdFilterPlugin::pythonFilterName(FilterId id) const {
    switch (id) {
        case FP_COMPUTE_NORMALS: return "compute_normals_nbhd";
        case FP_COMPUTE_CURVATURES: return "compute_curvatures_nbhd";
        case FP_ISOTROPIC_SMOOTHING: return "smooth_isotropic_nbhd";
        case FP_ANISOTROPIC_SMOOTHING: return "smooth_anisotropic_nbhd";
    }
    throw nbhd_filter_error(NBHD_STATUS_INVALID_ARGUMENT, "unknown filter id " + std::to_string(int(id)));
}

std::string NbhdFilterPlugin::filterInfo(FilterId id) const {
    const std::string nb =
        "Neighbourhoods are the eps-k-neighbourhoods of Section 2.1.1: the k nearest other vertices "
        "within the influence radius eps (by default in units of the mean nearest-neighbour "
        "spacing h), found exactly with nbhd's kd-tree (Chapters 3 and 5).<br/>";
    std::string text;
    switch (id) {
        case FP_COMPUTE_NORMALS:
            text = "Per-vertex normals of the point set: the eigenvector of the smallest eigenvalue "
                   "of the covariance of each vertex and its neighbourhood (Section 2.1.2, eq. 2.8-2.10), "
                   "optionally oriented consistently. Faces are ignored.<br/>" + nb;
            break;
        case FP_COMPUTE_CURVATURES:
            text = "Per-vertex curvature stored as vertex quality: the principal curvatures of the "
                   "discrete Weingarten map estimated from the directional curvatures to the "
                   "neighbours (Section 2.2, eq. 2.25-2.29), and the other values the thesis' "
                   "program colours by (Section 7.3: Mean, Max Princ, CovQuotient, PrincQuotient, "
                   "MaxCov). Normals are written too.<br/>" + nb;
            break;
        case FP_ISOTROPIC_SMOOTHING:
            text = "Isotropic Laplacian (Gaussian) fairing of the vertex positions: each step moves "
                   "every vertex by tau times the mean of the vectors to its neighbours "
                   "(Section 2.1.3, eq. 2.16-2.18). Connectivity is not used or changed. Normals "
                   "and mean curvature (as quality) of the result are written.<br/>" + nb;
            break;
        case FP_ANISOTROPIC_SMOOTHING:
            text = "Anisotropic mean curvature flow (Section 2.3): as isotropic fairing, but each "
                   "neighbour is weighted by g_sharp (eq. 2.31) or g_cont (eq. 2.32) of its "
                   "directional curvature against the threshold lambda, so that edges and corners "
                   "are kept; the feature criterion Q, K or D (eq. 2.33-2.35) restricts the "
                   "anisotropic weights to feature points. Normals and mean curvature (as quality) "
                   "of the result are written.<br/>" + nb;
            break;
        default: filterName(id);  // throws
    }
    return text + "See:<br/>" + kThesis + "Chapter 2 and Section 7.3.";
}

int NbhdFilterPlugin::getClass(FilterId id) const {
    switch (id) {
        case FP_COMPUTE_NORMALS: return Normal | PointSet;
        case FP_COMPUTE_CURVATURES: return Normal | Quality | PointSet;
        case FP_ISOTROPIC_SMOOTHING:
        case FP_ANISOTROPIC_SMOOTHING: return Smoothing | PointSet;
    }
    filterName(id);  // throws
    return 0;
}

RichParameterList NbhdFilterPlugin::initParameterList(FilterId id) const {
    filterName(id);  // rejects an unknown id
    const nbhd_smooth_options d = nbhd_smooth_options_default();
    RichParameterList l;
    l.add(param("k", "Maximum valence k: the neighbourhood is at most the k nearest other vertices",
                T::Int, double(d.k), 1, 100));
    l.add(param("epsilon",
                "Influence radius eps: neighbours lie within this distance, in units of the mean "
                "nearest-neighbour spacing h unless epsilon_absolute is set",
                T::Float, d.epsilon, 0.5, 50));
    l.add(param("epsilon_absolute", "eps is in the mesh's own units instead of multiples of h",
                T::Bool, 0, 0, 1));
    if (id == FP_ISOTROPIC_SMOOTHING || id == FP_ANISOTROPIC_SMOOTHING) {
        l.add(param("steps", "Number of smoothing steps", T::Int, double(d.steps), 0, 100));
        l.add(param("tau", "Step size tau: the fraction of the umbrella vector applied per step",
                    T::Float, d.tau, 0, 1));
        l.add(param("update_neighbors",
                    "Recompute the neighbourhoods before every step (thesis: 'Update Neighbors')",
                    T::Bool, d.update_neighbors ? 1 : 0, 0, 1));
    }
    if (id == FP_ANISOTROPIC_SMOOTHING) {
        l.add(param("weighting",
                    "Weights of the neighbours: sharp = g_sharp (eq. 2.31, 0 from lambda on), "
                    "continuous = g_cont (eq. 2.32)",
                    T::Enum, d.weighting == NBHD_WEIGHTING_CONTINUOUS ? 1 : 0, 0, 1, kWeightings));
        l.add(param("lambda",
                    "Curvature threshold lambda: neighbours with a larger directional curvature are "
                    "not (g_sharp) or less (g_cont) smoothed towards; in units of 1/h unless "
                    "lambda_absolute is set",
                    T::Float, d.lambda, 0.01, 5));
        l.add(param("lambda_absolute", "lambda is in inverse mesh units instead of multiples of 1/h",
                    T::Bool, 0, 0, 1));
        l.add(param("feature",
                    "Feature criterion: which vertices are smoothed anisotropically (the others "
                    "isotropically): all, Q = edge quotient min/max principal curvature below the "
                    "threshold (eq. 2.33), K = max principal curvature above it (eq. 2.34), D = a "
                    "directional curvature above it (eq. 2.35)",
                    T::Enum, double(d.feature), 0, 3, kFeatures));
        l.add(param("feature_threshold",
                    "Threshold of the feature criterion: a quotient for Q, a curvature in units of "
                    "1/h for K and D",
                    T::Float, d.feature_threshold, 0, 5));
    }
    if (id == FP_COMPUTE_CURVATURES)
        l.add(param("quality",
                    "What becomes the vertex quality: mean curvature (k1+k2)/2, max principal "
                    "curvature max(|k1|,|k2|), covariance quotient, principal curvature quotient, "
                    "max covariance (thesis Section 7.3's colourings)",
                    T::Enum, 0, 0, double(kQualities.size() - 1), kQualities));
    l.add(param("orientation",
                "Orientation of the written normals (and so the sign of the mean curvature): none "
                "(the eigen-solver's sign), propagate (consistent along the neighbour graph), "
                "away_from_centroid",
                T::Enum, id == FP_COMPUTE_NORMALS ? 0 : 1, 0, 2, kOrientations));
    return l;
}

void NbhdFilterPlugin::initParameterList(FilterId id, const VertexArray&, RichParameterList& params) const {
    const RichParameterList declared = initParameterList(id);
    for (const RichParameter& p : declared.parameters()) params.add(p);
}

std::map<std::string, double> NbhdFilterPlugin::applyFilter(FilterId id, VertexArray& mesh,
                                                            const RichParameterList& params,
                                                            const ProgressCallback& progress) const {
    const std::string name = filterName(id);
    if (mesh.xyz.size() % 3 != 0)
        throw nbhd_filter_error(NBHD_STATUS_INVALID_ARGUMENT,
                                name + ": the vertex array's size is not a multiple of 3");
    // Every parameter the filter declares must be present (and nothing else is read).
    const RichParameterList declared = initParameterList(id);
    for (const RichParameter& p : declared.parameters())
        if (!params.has(p.name))
            throw nbhd_filter_error(NBHD_STATUS_INVALID_ARGUMENT, name + ": parameter '" + p.name + "' is missing");

    Reader r(params, name);
    nbhd_smooth_options o = nbhd_smooth_options_default();
    o.k = r.whole("k", NBHD_STATUS_INVALID_K);
    o.epsilon = r.real("epsilon");
    o.epsilon_units = units(r.flag("epsilon_absolute"));
    const std::size_t orientation = r.choice("orientation");
    const std::size_t n = mesh.size();
    if (orientation == 1) {
        o.orientation = NBHD_ORIENTATION_PROPAGATE;
    } else if (orientation == 2) {
        o.orientation = NBHD_ORIENTATION_AWAY_FROM_POINT;
        double c[3] = {0, 0, 0};
        for (std::size_t i = 0; i < n; ++i)
            for (int j = 0; j < 3; ++j) c[j] += mesh.xyz[3 * i + j];
        for (int j = 0; j < 3; ++j) o.orientation_point[j] = n ? c[j] / double(n) : 0;
    }
    if (id == FP_ISOTROPIC_SMOOTHING || id == FP_ANISOTROPIC_SMOOTHING) {
        o.steps = r.whole("steps");
        o.tau = r.real("tau");
        o.update_neighbors = r.flag("update_neighbors");
        o.weighting = NBHD_WEIGHTING_ISOTROPIC;
    }
    if (id == FP_ANISOTROPIC_SMOOTHING) {
        o.weighting = r.choice("weighting") == 1 ? NBHD_WEIGHTING_CONTINUOUS : NBHD_WEIGHTING_SHARP;
        o.lambda = r.real("lambda");
        o.lambda_units = units(r.flag("lambda_absolute"));
        o.feature = nbhd_feature_criterion(r.choice("feature"));  // choices in nbhd's order
        o.feature_threshold = r.real("feature_threshold");
    }
    std::size_t quality = 0;
    if (id == FP_COMPUTE_CURVATURES) quality = r.choice("quality");

    ProgressBridge bridge;
    if (progress) {
        bridge.callback = &progress;
        o.progress = &ProgressBridge::call;
        o.progress_user_data = &bridge;
    }

    // nbhd writes nothing unless it succeeds, and normals and quality go to buffers that replace
    // the mesh's at the end: a failure leaves the mesh as it was.
    const nbhd_points pts = {mesh.xyz.data(), n, 3, 3 * sizeof(float), NBHD_SCALAR_TYPE_F32};
    auto fail_if = [&](nbhd_status s) {
        if (bridge.error) std::rethrow_exception(bridge.error);
        if (s == NBHD_STATUS_OK) return;
        // nbhd's message names its option field, which is the parameter's name; only a bad k has
        // its own status and a message that does not say "k" as a name.
        std::string where = s == NBHD_STATUS_INVALID_K ? "parameter 'k': " : "";
        throw nbhd_filter_error(s, name + ": " + where + nbhd_last_error_message() + " [" +
                                       nbhd_status_string(s) + "]");
    };

    std::map<std::string, double> out;
    std::vector<float> normals(3 * n), qual;
    std::size_t degenerate = 0;
    if (id == FP_COMPUTE_NORMALS) {
        std::vector<std::uint8_t> flags(n);
        // The normals' own options: the neighbourhood, orientation and callback chosen above.
        nbhd_normal_options no = nbhd_normal_options_default();
        no.k = o.k;
        no.epsilon = o.epsilon;
        no.epsilon_units = o.epsilon_units;
        no.orientation = o.orientation;
        for (int j = 0; j < 3; ++j) no.orientation_point[j] = o.orientation_point[j];
        no.threads = o.threads;
        no.progress = o.progress;
        no.progress_user_data = o.progress_user_data;
        // Written as floats straight into `normals` (packed x, y, z).
        nbhd_normals_output nout{};
        nout.normals = normals.data();
        nout.normals_stride = 0;
        nout.scalar_type = NBHD_SCALAR_TYPE_F32;
        nout.flags = flags.data();
        fail_if(nbhd_estimate_normals(&pts, &no, &nout));
        degenerate = std::size_t(std::count_if(flags.begin(), flags.end(), [](std::uint8_t f) { return f != 0; }));
    } else {
        std::vector<nbhd_point_geometry> g(n);
        nbhd_smooth_summary sum{};
        if (id == FP_COMPUTE_CURVATURES) {
            fail_if(nbhd_estimate_curvatures(&pts, &o, g.data(), &sum));
        } else {
            // In place: nbhd reads all points before writing, and writes nothing on failure.
            fail_if(nbhd_smooth(&pts, &o, mesh.xyz.data(), g.data(), &sum));
        }
        qual.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            for (int j = 0; j < 3; ++j) normals[3 * i + j] = float(g[i].normal[j]);
            if (g[i].normal_flags != 0) ++degenerate;
            double q = g[i].mean_curvature;
            switch (quality) {
                case 1: q = g[i].max_principal_curvature; break;
                case 2: q = g[i].covariance_quotient; break;
                case 3: q = g[i].principal_curvature_quotient; break;
                case 4: q = g[i].max_covariance; break;
                default: break;
            }
            qual[i] = float(q);
        }
        out["spacing"] = sum.spacing;
        out["epsilon"] = sum.epsilon;
        if (id == FP_ANISOTROPIC_SMOOTHING) out["lambda"] = sum.lambda;
        out["min_neighbors"] = double(sum.min_neighbors);
        if (!qual.empty()) {
            auto mm = std::minmax_element(qual.begin(), qual.end());
            out["quality_min"] = *mm.first;
            out["quality_max"] = *mm.second;
        }
        mesh.quality.swap(qual);
    }
    mesh.normals.swap(normals);
    out["degenerate_normals"] = double(degenerate);
    return out;
}

}  // namespace nbhd_meshlab
