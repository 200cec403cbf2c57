// Exact distance of points to a triangle mesh's surface, for measuring smoothing: the closest
// point on each candidate triangle, the candidates found with nbhd's own radius query around
// the mesh's vertices. Header-only; needs nbhd.hpp.
#pragma once

#include <nbhd.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace examples {

struct V3 {
    double x, y, z;
};
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

/// Squared distance of p to triangle (a, b, c): the closest point is found by walking the
/// Voronoi regions of the vertices, edges and face (Ericson, Real-Time Collision Detection,
/// Section 5.1.5), in double.
inline double sq_dist_to_triangle(V3 p, V3 a, V3 b, V3 c) {
    V3 ab = b - a, ac = c - a, ap = p - a;
    double d1 = dot(ab, ap), d2 = dot(ac, ap);
    V3 q;
    if (d1 <= 0 && d2 <= 0) {
        q = a;
    } else {
        V3 bp = p - b;
        double d3 = dot(ab, bp), d4 = dot(ac, bp);
        V3 cp = p - c;
        double d5 = dot(ab, cp), d6 = dot(ac, cp);
        double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
        if (d3 >= 0 && d4 <= d3) q = b;
        else if (d6 >= 0 && d5 <= d6) q = c;
        else if (vc <= 0 && d1 >= 0 && d3 <= 0) q = a + (d1 / (d1 - d3)) * ab;
        else if (vb <= 0 && d2 >= 0 && d6 <= 0) q = a + (d2 / (d2 - d6)) * ac;
        else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
            q = b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
        else {
            double den = 1.0 / (va + vb + vc);
            q = a + (vb * den) * ab + (vc * den) * ac;
        }
    }
    V3 d = p - q;
    return dot(d, d);
}

/// Distances to the surface of a triangle mesh (vertices: packed x, y, z floats). The closest
/// surface point s of q is no farther than q's nearest vertex (distance d_nn), and s lies in a
/// triangle whose vertices are within the longest edge L of s; so the triangles around the
/// vertices within d_nn + L of q contain it.
class SurfaceDistance {
public:
    SurfaceDistance(std::vector<float> xyz, std::vector<std::array<std::uint32_t, 3>> tris)
        : xyz_(std::move(xyz)),
          tris_(std::move(tris)),
          tree_(nbhdpp::build(nbhdpp::points_f32(xyz_.data(), xyz_.size() / 3, 3 * sizeof(float)),
                              nbhd_build_options_default())) {
        faces_of_.resize(xyz_.size() / 3);
        for (std::uint32_t f = 0; f < tris_.size(); ++f)
            for (int j = 0; j < 3; ++j) {
                faces_of_[tris_[f][j]].push_back(f);
                V3 e = at(tris_[f][j]) - at(tris_[f][(j + 1) % 3]);
                longest_ = std::max(longest_, std::sqrt(dot(e, e)));
            }
        stamp_.assign(tris_.size(), 0);
    }

    /// Distance of the point q (x, y, z) to the surface.
    double operator()(const float* q) {
        nbhdpp::knn(tree_.get(), q, 1, nn_);
        double r = std::sqrt(double(nn_.sq[0])) + longest_;
        nbhdpp::radius(tree_.get(), q, r * (1 + 1e-6), near_);
        ++round_;
        V3 p{q[0], q[1], q[2]};
        double best = double(nn_.sq[0]);
        for (std::uint32_t v : near_.idx)
            for (std::uint32_t f : faces_of_[v]) {
                if (stamp_[f] == round_) continue;
                stamp_[f] = round_;
                best = std::min(best, sq_dist_to_triangle(p, at(tris_[f][0]), at(tris_[f][1]),
                                                          at(tris_[f][2])));
            }
        return std::sqrt(best);
    }

    /// RMS and maximum distance of `n` points (packed x, y, z floats).
    struct Stats {
        double rms = 0, max = 0;
    };
    Stats stats(const float* pts, std::size_t n) {
        Stats s;
        for (std::size_t i = 0; i < n; ++i) {
            double t = (*this)(pts + 3 * i);
            s.rms += t * t;
            s.max = std::max(s.max, t);
        }
        s.rms = n ? std::sqrt(s.rms / double(n)) : 0;
        return s;
    }

private:
    V3 at(std::uint32_t i) const { return {xyz_[3 * i], xyz_[3 * i + 1], xyz_[3 * i + 2]}; }
    std::vector<float> xyz_;
    std::vector<std::array<std::uint32_t, 3>> tris_;
    nbhdpp::Tree tree_;
    double longest_ = 0;
    std::vector<std::vector<std::uint32_t>> faces_of_;
    std::vector<std::uint64_t> stamp_;
    std::uint64_t round_ = 0;
    nbhdpp::Result nn_, near_;
};

}  // namespace examples
