// A filter plugin with the shape of MeshLab's FilterPlugin interface
// (src/common/plugins/interfaces/filter_plugin.h: types(), filterName(id), filterInfo(id),
// getClass(id), initParameterList(id, mesh, params), applyFilter(id, mesh, params, callback)
// throwing on error), implemented over nbhd's C API on a plain vertex array and without Qt or
// VCG, so that a MeshLab plugin can forward to it:
//
//   - QString filterName(ActionIDType id) const  -> QString::fromStdString(shim.filterName(id))
//   - initParameterList(...)                     -> one RichInt / RichFloat / RichBool /
//                                                   RichEnum per RichParameter (name,
//                                                   default, description; min/max as a
//                                                   RichDynamicFloat's range)
//   - applyFilter(..., vcg::CallBackPos* cb)      -> copy the vertices into a VertexArray (or
//                                                   point it at them), call applyFilter with
//                                                   [cb](double f, const char* s) {
//                                                       return cb(int(100 * f), s); },
//                                                   copy normals / quality back, and rethrow
//                                                   nbhd_filter_error as MLException.
//
// Filters: normals, curvatures (as per-vertex quality), isotropic and anisotropic smoothing, all
// from M. Skrodzki, "Neighborhood Computation of Point Set Surfaces", Chapter 2; parameters in
// its terms (Section 7.3): k (maximum valence), epsilon (influence radius), steps, tau, lambda
// (curvature threshold), the weighting g_sharp / g_cont and the feature criterion Q / K / D.
#pragma once

#include <nbhd.h>

#include <cstddef>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace nbhd_meshlab {

/// The mesh a filter works on: vertices only (the filters are point-set methods; faces are
/// neither needed nor changed). `xyz` is read and, by the smoothing filters, written in place
/// (3 floats per vertex, packed: nbhd reads it with a stride of 12 bytes). `normals` (3 floats
/// per vertex) and `quality` (1 per vertex) are outputs, resized by the filters that write them.
struct VertexArray {
    std::vector<float> xyz;
    std::vector<float> normals;
    std::vector<float> quality;
    std::size_t size() const { return xyz.size() / 3; }
};

/// What applyFilter throws (MeshLab's plugins throw MLException): the nbhd status and a message
/// naming the filter and the parameter at fault. For failures of nbhd itself the message ends
/// with nbhd_last_error_message(); for errors the shim finds before calling nbhd (an unknown
/// parameter, a k that is not a whole number) the status is the one nbhd would use
/// (NBHD_STATUS_INVALID_ARGUMENT, NBHD_STATUS_INVALID_K).
class nbhd_filter_error : public std::runtime_error {
public:
    nbhd_filter_error(nbhd_status status, const std::string& message)
        : std::runtime_error(message), status_(status) {}
    nbhd_status status() const { return status_; }

private:
    nbhd_status status_;
};

/// One parameter, like MeshLab's RichParameter subclasses: a name (the key, as pymeshlab
/// spells parameters), a description (label and tooltip), a default, and a range. Every value
/// is held as a double; Int and Enum values must be whole numbers (Enum: an index into
/// `choices`), Bool values 0 or 1. [min, max] is the range a dialog offers (a
/// RichDynamicFloat's slider); the values nbhd cannot use are rejected by nbhd when the filter
/// runs, and the exception names the parameter.
struct RichParameter {
    enum class Type { Int, Float, Bool, Enum };
    std::string name;
    std::string description;
    Type type = Type::Float;
    double default_value = 0;
    double min = 0;
    double max = 0;
    std::vector<std::string> choices;  // Enum only
    double value = 0;
};

/// An ordered list of parameters with lookup by name (MeshLab's RichParameterList).
class RichParameterList {
public:
    void add(RichParameter p);
    bool has(const std::string& name) const;
    const RichParameter& get(const std::string& name) const;  // throws nbhd_filter_error
    /// Sets a value; throws nbhd_filter_error (INVALID_ARGUMENT) for an unknown name.
    void set(const std::string& name, double value);
    /// Sets an Enum parameter by its choice's name; throws for an unknown name or choice.
    void setEnum(const std::string& name, const std::string& choice);
    const std::vector<RichParameter>& parameters() const { return params_; }

private:
    std::vector<RichParameter> params_;
};

class NbhdFilterPlugin {
public:
    /// The filter ids (MeshLab's FilterIDType enum of a plugin).
    enum FilterId {
        FP_COMPUTE_NORMALS = 0,
        FP_COMPUTE_CURVATURES = 1,
        FP_ISOTROPIC_SMOOTHING = 2,
        FP_ANISOTROPIC_SMOOTHING = 3,
    };
    /// MeshLab's FilterPlugin::FilterClass bits that these filters use.
    enum FilterClass { Smoothing = 0x00080, Quality = 0x00100, Normal = 0x00800, PointSet = 0x08000 };

    /// Progress: `fraction` from 0 to 1 as nbhd reports it (MeshLab's vcg::CallBackPos takes
    /// an int percentage: pass int(100 * fraction)) and the stage nbhd is in. Return false to
    /// cancel: applyFilter then throws nbhd_filter_error with NBHD_STATUS_CANCELLED and leaves the
    /// mesh unchanged. An exception thrown by the callback stops the run the same way and is
    /// rethrown from applyFilter.
    using ProgressCallback = std::function<bool(double fraction, const char* stage)>;

    NbhdFilterPlugin();

    /// The filter ids, in menu order (FilterPlugin::types()).
    const std::vector<FilterId>& types() const { return types_; }
    /// The menu entry (a few words).
    std::string filterName(FilterId id) const;
    /// pymeshlab-style name: compute_normals_nbhd, ...
    std::string pythonFilterName(FilterId id) const;
    /// The long description with the reference to the thesis (simple HTML, as MeshLab shows it).
    std::string filterInfo(FilterId id) const;
    int getClass(FilterId id) const;
    /// The parameters of a filter with their defaults (the mesh is not needed: lengths are
    /// relative to the sample spacing by default).
    RichParameterList initParameterList(FilterId id) const;
    void initParameterList(FilterId id, const VertexArray& mesh, RichParameterList& params) const;

    /// Runs a filter. Returns the scalars the run resolved (MeshLab's applyFilter returns such a
    /// map for pymeshlab): "spacing" (nbhd's mean nearest-neighbour distance h, when computed),
    /// "epsilon" and "lambda" in absolute units, "min_neighbors", "degenerate_normals",
    /// "quality_min" / "quality_max". Throws nbhd_filter_error on any error; the mesh is then
    /// unchanged.
    std::map<std::string, double> applyFilter(FilterId id, VertexArray& mesh,
                                              const RichParameterList& params,
                                              const ProgressCallback& progress = {}) const;

private:
    std::vector<FilterId> types_;
};

}  // namespace nbhd_meshlab
