// nbhd.hpp: a thin C++ layer over nbhd's C API (nbhd.h), installed next to it by
// scripts/install.sh. Header-only, C++14 or later, namespace nbhdpp:
//
//   - owning handles that free themselves (nbhdpp::Tree, nbhdpp::Table: std::unique_ptr with
//     nbhd_tree_free / nbhd_neighborhoods_free as deleter);
//   - statuses turned into exceptions (nbhdpp::Error carries the nbhd_status and nbhd's message,
//     read on the calling thread right after the failed call);
//   - query helpers that grow their buffers when nbhd answers NBHD_STATUS_BUFFER_TOO_SMALL, and
//     the tree's nodes, tree order and node weight sums as vectors sized the same way.
//
// It adds no behaviour: every function is one C call (or one retry after
// NBHD_STATUS_BUFFER_TOO_SMALL), so the C header's documentation applies unchanged. It depends on
// nothing but nbhd.h and the C++ standard library; with the CMake package (nbhd::nbhd) or
// pkg-config (`pkg-config --cflags nbhd`) it is found as <nbhd.hpp>. The C ABI's compatibility
// rules (cpp_examples/README.md, "ABI policy") apply to it too: it is inline code compiled into
// your program.
#pragma once

#include <nbhd.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace nbhdpp {

/// A failed nbhd call: the status and nbhd's message naming the argument at fault.
class Error : public std::runtime_error {
public:
    Error(nbhd_status status, const std::string& call)
        : std::runtime_error(call + ": " + nbhd_status_string(status) + " (" +
                             nbhd_last_error_message() + ")"),
          status_(status) {}
    nbhd_status status() const { return status_; }

private:
    nbhd_status status_;
};

inline void check(nbhd_status status, const char* call) {
    if (status != NBHD_STATUS_OK) throw Error(status, call);
}

struct TreeFree {
    void operator()(nbhd_tree* t) const { nbhd_tree_free(t); }
};
struct TableFree {
    void operator()(nbhd_neighborhoods* t) const { nbhd_neighborhoods_free(t); }
};
using Tree = std::unique_ptr<nbhd_tree, TreeFree>;
using Table = std::unique_ptr<nbhd_neighborhoods, TableFree>;

/// Points of dimension 3 in f32, read in place from `data` with `stride` bytes per point.
inline nbhd_points points_f32(const float* data, std::size_t count, std::size_t stride) {
    return nbhd_points{data, count, 3, stride, NBHD_SCALAR_TYPE_F32};
}

inline Tree build(const nbhd_points& points, const nbhd_build_options& options) {
    nbhd_tree* t = nullptr;
    check(nbhd_tree_build(&points, &options, &t), "nbhd_tree_build");
    return Tree(t);
}

inline nbhd_stats stats(const nbhd_tree* tree) {
    nbhd_stats s{};
    check(nbhd_tree_stats(tree, &s), "nbhd_tree_stats");
    return s;
}

/// Calls `f(buffer, capacity, &count)` with no buffer to learn the size, then once with a
/// buffer of that size (nbhd answers the first call with NBHD_STATUS_BUFFER_TOO_SMALL).
template <class V, class F>
std::vector<V> sized(const char* call, F&& f) {
    std::size_t n = 0;
    nbhd_status s = f(static_cast<V*>(nullptr), 0, &n);
    std::vector<V> out(n);
    if (s == NBHD_STATUS_BUFFER_TOO_SMALL) s = f(out.data(), n, &n);
    check(s, call);
    out.resize(n);
    return out;
}

/// The tree's nodes in preorder (nbhd_tree_nodes).
inline std::vector<nbhd_node> nodes(const nbhd_tree* tree) {
    return sized<nbhd_node>("nbhd_tree_nodes", [&](nbhd_node* b, std::size_t cap, std::size_t* n) {
        return nbhd_tree_nodes(tree, b, cap, n);
    });
}

/// The caller indices in tree order (nbhd_tree_order): a node's points are
/// `order[node.start .. node.end - 1]`.
inline std::vector<std::uint32_t> tree_order(const nbhd_tree* tree) {
    return sized<std::uint32_t>("nbhd_tree_order",
                                [&](std::uint32_t* b, std::size_t cap, std::size_t* n) {
                                    return nbhd_tree_order(tree, b, cap, n);
                                });
}

/// Per-node sums of `weights` (one per point given to the build), in the order of nodes()
/// (nbhd_tree_node_weights).
inline std::vector<double> node_weights(const nbhd_tree* tree, const std::vector<double>& weights) {
    return sized<double>("nbhd_tree_node_weights", [&](double* b, std::size_t cap, std::size_t* n) {
        return nbhd_tree_node_weights(tree, weights.data(), weights.size(), b, cap, n);
    });
}

/// The table of `spec` for every stored point, with or without each point in its own row.
inline Table neighborhoods(const nbhd_tree* tree, const nbhd_neighborhood_spec& spec,
                           bool exclude_self, std::size_t threads = 0) {
    nbhd_table_options o = nbhd_table_options_default();
    o.exclude_self = exclude_self;
    o.threads = threads;
    nbhd_neighborhoods* t = nullptr;
    check(nbhd_tree_neighborhoods(tree, &spec, &o, &t), "nbhd_tree_neighborhoods");
    return Table(t);
}

/// One row of an f32 table, pointing into the table.
struct Row {
    const std::uint32_t* idx = nullptr;
    const float* sq = nullptr;
    std::size_t len = 0;
};

/// Row `i` through the table's offset arrays (no call per row), bounds-checked.
class RowsF32 {
public:
    explicit RowsF32(const nbhd_neighborhoods* t)
        : rows_(nbhd_neighborhoods_rows(t)),
          off_(nbhd_neighborhoods_offsets(t)),
          idx_(nbhd_neighborhoods_indices(t)),
          sq_(static_cast<const float*>(nbhd_neighborhoods_sq_dists(t))) {}
    std::size_t rows() const { return rows_; }
    /// Row `i`; throws std::out_of_range for `i` >= rows() (the offsets end there).
    Row operator[](std::size_t i) const {
        if (i >= rows_) throw std::out_of_range("nbhdpp::RowsF32: row " + std::to_string(i) +
                                                " of " + std::to_string(rows_));
        return Row{idx_ + off_[i], sq_ + off_[i], off_[i + 1] - off_[i]};
    }

private:
    std::size_t rows_;
    const std::size_t* off_;
    const std::uint32_t* idx_;
    const float* sq_;
};

/// A query's result, ordered by (squared distance, index) as nbhd returns it.
struct Result {
    std::vector<std::uint32_t> idx;
    std::vector<float> sq;
    std::size_t size() const { return idx.size(); }
};

/// Calls `f(indices, sq_dists, capacity, &count)` and grows the buffers once if nbhd asks for
/// more (radius queries do not know their size in advance).
template <class F>
void query_into(Result& out, std::size_t initial, const char* call, F&& f) {
    if (out.idx.size() < initial) {
        out.idx.resize(initial);
        out.sq.resize(initial);
    }
    std::size_t cap = out.idx.size(), count = 0;
    nbhd_status s = f(out.idx.data(), out.sq.data(), cap, &count);
    if (s == NBHD_STATUS_BUFFER_TOO_SMALL) {
        out.idx.resize(count);
        out.sq.resize(count);
        s = f(out.idx.data(), out.sq.data(), count, &count);
    }
    check(s, call);
    out.idx.resize(count);
    out.sq.resize(count);
}

inline void knn(const nbhd_tree* tree, const float* q, std::size_t k, Result& out) {
    query_into(out, k, "nbhd_tree_knn", [&](std::uint32_t* i, float* d, std::size_t cap, std::size_t* n) {
        return nbhd_tree_knn(tree, q, k, i, d, cap, n);
    });
}

inline void radius(const nbhd_tree* tree, const float* q, double r, Result& out) {
    query_into(out, 64, "nbhd_tree_radius", [&](std::uint32_t* i, float* d, std::size_t cap, std::size_t* n) {
        return nbhd_tree_radius(tree, q, r, i, d, cap, n);
    });
}

inline void knn_radius(const nbhd_tree* tree, const float* q, std::size_t k, double r, Result& out) {
    query_into(out, k, "nbhd_tree_knn_radius",
               [&](std::uint32_t* i, float* d, std::size_t cap, std::size_t* n) {
                   return nbhd_tree_knn_radius(tree, q, k, r, i, d, cap, n);
               });
}

inline void knn_index(const nbhd_tree* tree, std::size_t index, bool exclude_self, std::size_t k,
                      Result& out) {
    query_into(out, k, "nbhd_tree_knn_index",
               [&](std::uint32_t* i, float* d, std::size_t cap, std::size_t* n) {
                   return nbhd_tree_knn_index(tree, index, exclude_self, k, i, d, cap, n);
               });
}

inline const char* pivot_name(nbhd_pivot_policy p) {
    switch (p) {
        case NBHD_PIVOT_POLICY_CYCLIC_MEDIAN: return "cyclic-median";
        case NBHD_PIVOT_POLICY_SPREAD_MEDIAN: return "spread-median";
        case NBHD_PIVOT_POLICY_CLOSEST_TO_MIDDLE: return "closest-to-middle";
        case NBHD_PIVOT_POLICY_SLIDING_MIDPOINT: return "sliding-midpoint";
    }
    return "?";
}

constexpr nbhd_pivot_policy kAllPivots[] = {
    NBHD_PIVOT_POLICY_CYCLIC_MEDIAN, NBHD_PIVOT_POLICY_SPREAD_MEDIAN,
    NBHD_PIVOT_POLICY_CLOSEST_TO_MIDDLE, NBHD_PIVOT_POLICY_SLIDING_MIDPOINT};

}  // namespace nbhdpp
