// nbhd's filters in MeshLab 2020.09; see filter_nbhd.h and meshlab_plugin/README.md.
#include "filter_nbhd.h"

#include <nbhd.h>

#include <vcg/complex/algorithms/stat.h>
#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/algorithms/update/color.h>
#include <vcg/complex/algorithms/update/normal.h>

#include <cmath>
#include <vector>

namespace {

const char* const kThesis =
    "See:<br/><i>Martin Skrodzki</i><br/><b>\"Neighborhood Computation of Point Set "
    "Surfaces\"</b><br/>PhD thesis, Freie Universit&auml;t Berlin, 2019.<br/>";

const char* const kNeighbourhoods =
    "<br/>Neighbourhoods are the thesis' &epsilon;-k-neighbourhoods (Section 2.1.1): the k "
    "nearest other vertices within the influence radius &epsilon;, found exactly with nbhd's "
    "k-d tree (Chapters 3 and 5). &epsilon; is in units of the mean nearest-neighbour spacing "
    "h of the vertices (estimated by nbhd) unless 'epsilon is absolute' is checked, so the "
    "defaults suit a model in metres and one in millimetres alike. Faces are ignored and kept; "
    "deleted vertices are left out.<br/>";

// The orientation choices of the dialog, in this order.
const QStringList kOrientations = {
    "None (the eigen-solver's sign)",
    "Consistent (propagated over the neighbour graph)",
    "Away from the orientation point",
    "Toward the orientation point",
};

nbhd_orientation orientationOf(int choice)
{
    switch (choice) {
    case 1: return NBHD_ORIENTATION_PROPAGATE;
    case 2: return NBHD_ORIENTATION_AWAY_FROM_POINT;
    case 3: return NBHD_ORIENTATION_TOWARD_POINT;
    default: return NBHD_ORIENTATION_UNORIENTED;
    }
}

// Curvature measures written to the vertex quality, in this order.
const QStringList kMeasures = {
    "Mean curvature (k1 + k2) / 2",
    "Gaussian curvature k1 k2",
    "Maximum principal curvature max(|k1|, |k2|)",
    "Surface variation l0 / (l0 + l1 + l2)",
    "Principal quotient min(|k1|,|k2|) / max(|k1|,|k2|)",
};

double measureOf(int choice, const nbhd_point_geometry& g)
{
    switch (choice) {
    case 1: return g.k1 * g.k2;
    case 2: return g.max_principal_curvature;
    case 3: return g.covariance_quotient;
    case 4: return g.principal_curvature_quotient;
    default: return g.mean_curvature;
    }
}

const QStringList kWeightings = {
    "g_sharp (eq. 2.31): 0 from lambda on",
    "g_cont (eq. 2.32): decays continuously from lambda on",
};

const QStringList kFeatures = {
    "All points",
    "Q: edge quotient (eq. 2.33) below the threshold",
    "K: principal curvature (eq. 2.34) above the threshold",
    "D: some directional curvature (eq. 2.35) above the threshold",
};

const char* stageName(nbhd_stage s)
{
    switch (s) {
    case NBHD_STAGE_NEIGHBORS: return "nbhd: neighbourhoods";
    case NBHD_STAGE_GEOMETRY: return "nbhd: normals and curvatures";
    case NBHD_STAGE_STEP: return "nbhd: smoothing step";
    case NBHD_STAGE_OUTPUTS: return "nbhd: per-vertex outputs";
    case NBHD_STAGE_DONE: return "nbhd: done";
    }
    return "nbhd";
}

// nbhd's progress callback, forwarded to MeshLab's vcg::CallBackPos (percent, message). nbhd
// calls it on the calling thread (the options' `threads` stays 0), which is the thread MeshLab
// runs the filter on, so MeshLab's callback may update its progress bar. Returning false
// cancels the run (NBHD_STATUS_CANCELLED; nothing is written).
struct Progress {
    vcg::CallBackPos* cb = nullptr;
    int last = -1;

    static bool call(double fraction, nbhd_stage stage, void* user)
    {
        auto* self = static_cast<Progress*>(user);
        if (self->cb == nullptr) return true;
        int percent = int(std::floor(100.0 * fraction));
        if (percent == self->last && stage != NBHD_STAGE_DONE) return true;
        self->last = percent;
        return self->cb(percent, stageName(stage));
    }
};

// The live (not deleted) vertices of a mesh, packed as doubles for nbhd.
struct Vertices {
    std::vector<CVertexO*> verts;
    std::vector<double> xyz;

    explicit Vertices(CMeshO& m)
    {
        verts.reserve(m.vert.size());
        xyz.reserve(3 * m.vert.size());
        for (CVertexO& v : m.vert) {
            if (v.IsD()) continue;
            verts.push_back(&v);
            for (int c = 0; c < 3; ++c) xyz.push_back(double(v.P()[c]));
        }
    }

    nbhd_points points() const
    {
        return nbhd_points{xyz.data(), verts.size(), 3, 0, NBHD_SCALAR_TYPE_F64};
    }
};

nbhd_units units(bool absolute) { return absolute ? NBHD_UNITS_ABSOLUTE : NBHD_UNITS_RELATIVE; }

// The parameters every filter shares: k, epsilon and its units.
void addNeighbourhood(RichParameterList& par, int k, double epsilon, const char* which)
{
    par.addParam(RichInt("k", k, "k (maximum valence)",
                         QString("The neighbourhood of a vertex is at most its k nearest other "
                                 "vertices%1 (at least 1).").arg(which)));
    par.addParam(RichFloat("epsilon", float(epsilon), "epsilon (influence radius)",
                           "Neighbours lie within this distance: a multiple of the mean "
                           "nearest-neighbour spacing h unless 'epsilon is absolute' is checked "
                           "(then in the mesh's own units). Must be > 0."));
    par.addParam(RichBool("epsilon_absolute", false, "epsilon is absolute",
                          "Read epsilon in the mesh's own units instead of multiples of h."));
}

void addOrientation(RichParameterList& par, int def, const MeshModel& m)
{
    par.addParam(RichEnum("orientation", def, kOrientations, "Normal orientation",
                          "Covariance normals have no sign of their own. 'Consistent' spreads "
                          "one orientation over the neighbour graph along smooth paths (Hoppe "
                          "et al. 1992; in each connected part the highest vertex's normal has "
                          "z >= 0); 'Away from' / 'Toward' point every normal away from / toward "
                          "the orientation point (outward for star-shaped surfaces around it; "
                          "toward a scanner's viewpoint)."));
    par.addParam(RichPoint3f("orientation_point", vcg::Point3f::Construct(m.cm.bbox.Center()),
                             "Orientation point",
                             "The point of the 'Away from' / 'Toward' orientations. Default: "
                             "the centre of the bounding box."));
}

void readOrientation(const RichParameterList& par, nbhd_orientation& o, double point[3])
{
    o = orientationOf(par.getEnum("orientation"));
    vcg::Point3f p = par.getPoint3f("orientation_point");
    for (int c = 0; c < 3; ++c) point[c] = double(p[c]);
}

void addSmoothingCommon(RichParameterList& par, const nbhd_smooth_options& d)
{
    par.addParam(RichInt("steps", int(d.steps), "Steps", "Number of smoothing steps (0 only analyses)."));
    par.addParam(RichFloat("tau", float(d.tau), "tau (step size)",
                           "Each step moves a vertex by tau times the mean of the vectors to its "
                           "neighbours (eq. 2.16-2.18). Finite, >= 0."));
    par.addParam(RichBool("update_neighbors", d.update_neighbors, "Update neighbours",
                          "Recompute the neighbourhoods before every step (thesis Section 7.3, "
                          "'Update Neighbors'); otherwise they are computed once on the input."));
    par.addParam(RichBool("constrain_interior", d.constrain_interior, "Constrain interior",
                          "Hold fixed the vertices whose covariance quotient l0/(l0+l1+l2) is "
                          "below the interior threshold (thesis Section 7.3)."));
    par.addParam(RichFloat("interior_threshold", float(d.interior_threshold), "Interior threshold",
                           "The covariance-quotient threshold of 'Constrain interior'."));
}

// Negative whole numbers from the dialog or a script are errors, not huge size_t values.
bool nonNegative(const RichParameterList& par, const char* name, size_t& out, QString& err)
{
    int v = par.getInt(name);
    if (v < 0) {
        err = QString("parameter '%1' must be >= 0, got %2").arg(name).arg(v);
        return false;
    }
    out = size_t(v);
    return true;
}

}  // namespace

FilterNbhdPlugin::FilterNbhdPlugin()
{
    typeList << FP_NORMALS << FP_CURVATURES << FP_SMOOTH_ISOTROPIC << FP_SMOOTH_ANISOTROPIC
             << FP_SMOOTH_ROBUST;
    for (FilterIDType tt : types()) actionList << new QAction(filterName(tt), this);
}

QString FilterNbhdPlugin::pluginName() const { return "FilterNbhd"; }

QString FilterNbhdPlugin::filterName(FilterIDType id) const
{
    switch (id) {
    case FP_NORMALS: return "nbhd: Compute Normals (eps-k neighbourhoods)";
    case FP_CURVATURES: return "nbhd: Compute Curvatures as Quality";
    case FP_SMOOTH_ISOTROPIC: return "nbhd: Point Set Smoothing, Isotropic";
    case FP_SMOOTH_ANISOTROPIC: return "nbhd: Point Set Smoothing, Anisotropic Mean Curvature Flow";
    case FP_SMOOTH_ROBUST: return "nbhd: Point Set Smoothing, Robust (keeps edges)";
    }
    return "nbhd: unknown filter";
}

QString FilterNbhdPlugin::filterScriptFunctionName(FilterIDType id)
{
    switch (id) {
    case FP_NORMALS: return "nbhdComputeNormals";
    case FP_CURVATURES: return "nbhdComputeCurvatures";
    case FP_SMOOTH_ISOTROPIC: return "nbhdSmoothIsotropic";
    case FP_SMOOTH_ANISOTROPIC: return "nbhdSmoothAnisotropic";
    case FP_SMOOTH_ROBUST: return "nbhdSmoothRobust";
    }
    return "";
}

QString FilterNbhdPlugin::filterInfo(FilterIDType id) const
{
    QString text;
    switch (id) {
    case FP_NORMALS:
        text = "Per-vertex normals of the point set: the eigenvector of the smallest eigenvalue "
               "of the covariance of each vertex and its neighbourhood (thesis Section 2.1.2, "
               "eq. 2.8-2.10, as PCL's NormalEstimation computes it), oriented as asked.";
        break;
    case FP_CURVATURES:
        text = "Per-vertex curvature written to the vertex quality: the principal curvatures "
               "k1 >= k2 of the discrete Weingarten map estimated from the directional "
               "curvatures to the neighbours (thesis Section 2.2, eq. 2.25-2.29), or the "
               "surface variation of the covariance. Curvatures are signed relative to the "
               "normals, which are written too (so choose an orientation for a signed measure). "
               "Optionally the quality is mapped to a red-green-blue colour ramp, clamped to "
               "its 2nd and 98th percentiles.";
        break;
    case FP_SMOOTH_ISOTROPIC:
        text = "Isotropic Laplacian fairing of the vertex positions: each step moves every "
               "vertex by tau times the mean of the vectors to its neighbours (thesis Section "
               "2.1.3, eq. 2.16-2.18, g = 1). Connectivity is neither used nor changed; vertex "
               "normals of the result are written, face normals recomputed.";
        break;
    case FP_SMOOTH_ANISOTROPIC:
        text = "Anisotropic mean curvature flow (thesis Section 2.3): as isotropic fairing, but "
               "each neighbour is weighted by g_sharp (eq. 2.31) or g_cont (eq. 2.32) of its "
               "directional curvature against the threshold lambda, so that edges and corners "
               "are kept; the feature criterion Q, K or D (eq. 2.33-2.35) restricts the "
               "anisotropic weights to feature points, the others are smoothed isotropically. "
               "lambda is in units of 1/h unless 'lambda is absolute' is checked.";
        break;
    case FP_SMOOTH_ROBUST:
        text = "nbhd's robust smoothing: each iteration fits candidate planes on a wider "
               "neighbourhood (k_plane vertices), scores them with a biweight of the plane "
               "distances in units of the estimated noise, and moves each vertex onto the plane "
               "of the neighbours on its side of a feature; it stops when the noise estimate "
               "falls by less than the tolerance. Slower than the thesis' flow, but keeps sharp "
               "edges at noise of about one spacing.";
        break;
    default: return "unknown filter";
    }
    return "<p>" + text + "</p>" + kNeighbourhoods + "<br/>" + kThesis +
           "Computed by the nbhd library through its C ABI.";
}

FilterNbhdPlugin::FilterClass FilterNbhdPlugin::getClass(QAction* a)
{
    switch (ID(a)) {
    case FP_NORMALS: return FilterClass(Normal | PointSet);
    case FP_CURVATURES: return FilterClass(Normal | Quality | VertexColoring | PointSet);
    default: return FilterClass(Smoothing | PointSet);
    }
}

MeshFilterInterface::FILTER_ARITY FilterNbhdPlugin::filterArity(QAction*) const { return SINGLE_MESH; }

int FilterNbhdPlugin::getRequirements(QAction* a)
{
    return ID(a) == FP_CURVATURES ? int(MeshModel::MM_VERTQUALITY | MeshModel::MM_VERTCOLOR)
                                  : int(MeshModel::MM_NONE);
}

int FilterNbhdPlugin::getPreConditions(QAction*) const { return MeshModel::MM_VERTCOORD; }

int FilterNbhdPlugin::postCondition(QAction* a) const
{
    switch (ID(a)) {
    case FP_NORMALS: return MeshModel::MM_VERTNORMAL;
    case FP_CURVATURES:
        return MeshModel::MM_VERTNORMAL | MeshModel::MM_VERTQUALITY | MeshModel::MM_VERTCOLOR;
    default:
        return MeshModel::MM_VERTCOORD | MeshModel::MM_VERTNORMAL | MeshModel::MM_FACENORMAL;
    }
}

void FilterNbhdPlugin::initParameterSet(QAction* a, MeshModel& m, RichParameterList& par)
{
    const nbhd_normal_options dn = nbhd_normal_options_default();
    const nbhd_smooth_options ds = nbhd_smooth_options_default();
    const nbhd_robust_options dr = nbhd_robust_options_default();
    switch (ID(a)) {
    case FP_NORMALS:
        addNeighbourhood(par, int(dn.k), dn.epsilon, "");
        addOrientation(par, 1, m);
        break;
    case FP_CURVATURES:
        addNeighbourhood(par, int(ds.k), ds.epsilon, "");
        par.addParam(RichEnum("measure", 0, kMeasures, "Quality",
                              "What is written to the vertex quality. Curvatures are in inverse "
                              "mesh units, signed relative to the normals; the surface variation "
                              "(PCL's 'curvature') is a plain number in [0, 1/3]."));
        par.addParam(RichBool("colorize", true, "Colour by quality",
                              "Map the quality to the vertex colour (red-green-blue ramp, "
                              "clamped to the 2nd and 98th percentiles)."));
        addOrientation(par, 1, m);
        break;
    case FP_SMOOTH_ISOTROPIC:
        addNeighbourhood(par, int(ds.k), ds.epsilon, "");
        addSmoothingCommon(par, ds);
        addOrientation(par, 1, m);
        break;
    case FP_SMOOTH_ANISOTROPIC:
        addNeighbourhood(par, int(ds.k), ds.epsilon, "");
        addSmoothingCommon(par, ds);
        par.addParam(RichEnum("weighting", ds.weighting == NBHD_WEIGHTING_CONTINUOUS ? 1 : 0,
                              kWeightings, "Weighting",
                              "The weights g_ij of the neighbours (eq. 2.30-2.32)."));
        par.addParam(RichFloat("lambda", float(ds.lambda), "lambda (curvature threshold)",
                               "Neighbours whose directional curvature exceeds lambda are not "
                               "(g_sharp) or less (g_cont) smoothed toward. A multiple of 1/h "
                               "unless 'lambda is absolute' is checked. Must be > 0."));
        par.addParam(RichBool("lambda_absolute", false, "lambda is absolute",
                              "Read lambda in inverse mesh units instead of multiples of 1/h."));
        par.addParam(RichEnum("feature", 0, kFeatures, "Feature criterion",
                              "Which vertices are smoothed anisotropically; the others "
                              "isotropically (eq. 2.33-2.35)."));
        par.addParam(RichFloat("feature_threshold", float(ds.feature_threshold),
                               "Feature threshold",
                               "The threshold of the criterion: a plain quotient for Q, a "
                               "curvature for K and D (a multiple of 1/h unless 'feature "
                               "threshold is absolute' is checked)."));
        par.addParam(RichBool("feature_absolute", false, "feature threshold is absolute",
                              "Read a curvature threshold in inverse mesh units."));
        addOrientation(par, 1, m);
        break;
    case FP_SMOOTH_ROBUST:
        addNeighbourhood(par, int(dr.k), dr.epsilon, " (the umbrella the step averages over)");
        par.addParam(RichInt("k_plane", int(dr.k_plane), "k_plane",
                             "Size of the wider neighbourhood the candidate planes are fitted "
                             "and scored on (>= k)."));
        par.addParam(RichInt("max_iterations", int(dr.max_iterations), "Maximum iterations",
                             "Upper bound on the number of iterations."));
        par.addParam(RichFloat("tolerance", float(dr.tolerance), "Tolerance",
                               "Stop once an iteration lowered the noise estimate by less than "
                               "this fraction (>= 0; 0 runs all iterations)."));
        par.addParam(RichFloat("inlier_width", float(dr.inlier_width), "Inlier width",
                               "Width of the biweight of plane distances, in units of the "
                               "estimated noise (> 0)."));
        par.addParam(RichFloat("feature_angle", float(dr.feature_angle), "Feature angle (degrees)",
                               "Angle at which a neighbour counts as across a feature (> 0)."));
        par.addParam(RichFloat("tau", float(dr.tau), "tau (step size)", "Step size in (0, 1]."));
        par.addParam(RichBool("noise_scale", dr.noise_scale, "Scale from the noise",
                              "While the cloud reads as a ball of noise (noise of about two "
                              "spacings or more), iterate with k and k_plane tripled. Clouds "
                              "with less noise are smoothed the same either way."));
        addOrientation(par, 1, m);
        break;
    default: break;
    }
}

bool FilterNbhdPlugin::fail(FilterIDType id, const QString& what)
{
    errorMessage = filterName(id) + ": " + what;
    // meshlabserver prints the log, not errorMessage: put the reason there too.
    Log(GLLogStream::WARNING, qUtf8Printable(errorMessage));
    return false;
}

bool FilterNbhdPlugin::applyFilter(QAction* a, MeshDocument& md, const RichParameterList& par,
                                   vcg::CallBackPos* cb)
{
    const FilterIDType id = ID(a);
    MeshModel* mm = md.mm();
    if (mm == nullptr) return fail(id, "no current mesh");
    CMeshO& m = mm->cm;
    Vertices v(m);
    if (v.verts.empty()) return fail(id, "the mesh has no vertices");
    const nbhd_points pts = v.points();
    const size_t n = v.verts.size();
    Progress progress;
    progress.cb = cb;
    QString err;

    size_t k = 0;
    if (!nonNegative(par, "k", k, err)) return fail(id, err);
    const double epsilon = double(par.getFloat("epsilon"));
    const nbhd_units epsilonUnits = units(par.getBool("epsilon_absolute"));

    if (id == FP_NORMALS) {
        nbhd_normal_options o = nbhd_normal_options_default();
        o.k = k;
        o.epsilon = epsilon;
        o.epsilon_units = epsilonUnits;
        readOrientation(par, o.orientation, o.orientation_point);
        o.progress = &Progress::call;
        o.progress_user_data = &progress;
        std::vector<double> normals(3 * n);
        std::vector<uint8_t> flags(n);
        nbhd_normals_output out{normals.data(), 0, NBHD_SCALAR_TYPE_F64, nullptr, 0, flags.data()};
        nbhd_status s = nbhd_estimate_normals(&pts, &o, &out);
        if (s != NBHD_STATUS_OK) return fail(id, nbhd_last_error_message());
        size_t flagged = 0;
        for (size_t i = 0; i < n; ++i) {
            v.verts[i]->N() = Point3m(Scalarm(normals[3 * i]), Scalarm(normals[3 * i + 1]),
                                      Scalarm(normals[3 * i + 2]));
            flagged += flags[i] != 0;
        }
        Log("nbhd: normals of %zu vertices (%zu with a degenerate neighbourhood)", n, flagged);
        return true;
    }

    std::vector<nbhd_point_geometry> geometry(n);
    nbhd_smooth_summary summary{};
    std::vector<double> out(3 * n);
    nbhd_status s = NBHD_STATUS_OK;

    if (id == FP_SMOOTH_ROBUST) {
        nbhd_robust_options o = nbhd_robust_options_default();
        o.k = k;
        if (!nonNegative(par, "k_plane", o.k_plane, err)) return fail(id, err);
        if (!nonNegative(par, "max_iterations", o.max_iterations, err)) return fail(id, err);
        o.epsilon = epsilon;
        o.epsilon_units = epsilonUnits;
        o.tolerance = double(par.getFloat("tolerance"));
        o.inlier_width = double(par.getFloat("inlier_width"));
        o.feature_angle = double(par.getFloat("feature_angle"));
        o.tau = double(par.getFloat("tau"));
        o.noise_scale = par.getBool("noise_scale");
        readOrientation(par, o.orientation, o.orientation_point);
        o.progress = &Progress::call;
        o.progress_user_data = &progress;
        s = nbhd_smooth_robust(&pts, &o, out.data(), geometry.data(), &summary);
    } else {
        nbhd_smooth_options o = nbhd_smooth_options_default();
        o.k = k;
        o.epsilon = epsilon;
        o.epsilon_units = epsilonUnits;
        readOrientation(par, o.orientation, o.orientation_point);
        o.progress = &Progress::call;
        o.progress_user_data = &progress;
        if (id != FP_CURVATURES) {
            if (!nonNegative(par, "steps", o.steps, err)) return fail(id, err);
            o.tau = double(par.getFloat("tau"));
            o.update_neighbors = par.getBool("update_neighbors");
            o.constrain_interior = par.getBool("constrain_interior");
            o.interior_threshold = double(par.getFloat("interior_threshold"));
        }
        if (id == FP_SMOOTH_ISOTROPIC) o.weighting = NBHD_WEIGHTING_ISOTROPIC;
        if (id == FP_SMOOTH_ANISOTROPIC) {
            o.weighting = par.getEnum("weighting") == 1 ? NBHD_WEIGHTING_CONTINUOUS : NBHD_WEIGHTING_SHARP;
            o.lambda = double(par.getFloat("lambda"));
            o.lambda_units = units(par.getBool("lambda_absolute"));
            switch (par.getEnum("feature")) {
            case 1: o.feature = NBHD_FEATURE_CRITERION_EDGE_QUOTIENT; break;
            case 2: o.feature = NBHD_FEATURE_CRITERION_PRINCIPAL_CURVATURE; break;
            case 3: o.feature = NBHD_FEATURE_CRITERION_DIRECTIONAL_CURVATURE; break;
            default: o.feature = NBHD_FEATURE_CRITERION_ALL_POINTS; break;
            }
            o.feature_threshold = double(par.getFloat("feature_threshold"));
            o.feature_units = units(par.getBool("feature_absolute"));
        }
        if (id == FP_CURVATURES)
            s = nbhd_estimate_curvatures(&pts, &o, geometry.data(), &summary);
        else
            s = nbhd_smooth(&pts, &o, out.data(), geometry.data(), &summary);
    }
    if (s == NBHD_STATUS_CANCELLED) return fail(id, "cancelled; the mesh is unchanged");
    if (s != NBHD_STATUS_OK) return fail(id, nbhd_last_error_message());

    for (size_t i = 0; i < n; ++i) {
        const double* nn = geometry[i].normal;
        v.verts[i]->N() = Point3m(Scalarm(nn[0]), Scalarm(nn[1]), Scalarm(nn[2]));
    }
    Log("nbhd: %zu vertices, spacing h = %g, epsilon = %g, lambda = %g, smallest neighbourhood %zu",
        n, summary.spacing, summary.epsilon, summary.lambda, summary.min_neighbors);

    if (id == FP_CURVATURES) {
        mm->updateDataMask(MeshModel::MM_VERTQUALITY | MeshModel::MM_VERTCOLOR);
        const int measure = par.getEnum("measure");
        for (size_t i = 0; i < n; ++i) v.verts[i]->Q() = Scalarm(measureOf(measure, geometry[i]));
        if (par.getBool("colorize")) {
            vcg::Histogram<Scalarm> h;
            vcg::tri::Stat<CMeshO>::ComputePerVertexQualityHistogram(m, h);
            vcg::tri::UpdateColor<CMeshO>::PerVertexQualityRamp(m, h.Percentile(0.02f),
                                                                h.Percentile(0.98f));
        }
        return true;
    }

    for (size_t i = 0; i < n; ++i)
        v.verts[i]->P() = Point3m(Scalarm(out[3 * i]), Scalarm(out[3 * i + 1]), Scalarm(out[3 * i + 2]));
    vcg::tri::UpdateBounding<CMeshO>::Box(m);
    if (m.fn > 0) vcg::tri::UpdateNormal<CMeshO>::PerFaceNormalized(m);
    return true;
}

MESHLAB_PLUGIN_NAME_EXPORTER(FilterNbhdPlugin)
