// ASCII PLY as meshlabserver saves it with `-m vn vq vc sa` (vertex properties in any order,
// polygon faces split into triangles), and fandisk's OBJ: the test programs' file access.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace plyio {

using Tri = std::array<std::uint32_t, 3>;

struct Mesh {
    std::vector<float> xyz, normals, quality;
    std::vector<std::array<int, 3>> colors;
    std::vector<Tri> tris;
    size_t n() const { return xyz.size() / 3; }
};

inline Mesh readPly(const std::string& path)
{
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot open " + path);
    std::string line, element;
    size_t nv = 0, nf = 0;
    std::vector<std::string> props;
    bool ascii = false;
    while (std::getline(in, line)) {
        std::istringstream ls(line);
        std::string w;
        ls >> w;
        if (w == "format") {
            std::string f;
            ls >> f;
            ascii = f == "ascii";
        } else if (w == "element") {
            ls >> element;
            (element == "vertex" ? nv : nf) = 0;
            size_t c;
            ls >> c;
            if (element == "vertex") nv = c; else if (element == "face") nf = c;
        } else if (w == "property" && element == "vertex") {
            std::string type, name;
            ls >> type >> name;
            props.push_back(name);
        } else if (w == "end_header") {
            break;
        }
    }
    if (!ascii) throw std::runtime_error(path + ": not an ASCII PLY");
    Mesh m;
    std::map<std::string, int> at;
    for (size_t i = 0; i < props.size(); ++i) at[props[i]] = int(i);
    auto has = [&](const char* p) { return at.count(p) > 0; };
    bool hasN = has("nx"), hasQ = has("quality"), hasC = has("red");
    std::vector<double> v(props.size());
    for (size_t i = 0; i < nv; ++i) {
        for (double& x : v) in >> x;
        for (const char* c : {"x", "y", "z"}) m.xyz.push_back(float(v[at[c]]));
        if (hasN) for (const char* c : {"nx", "ny", "nz"}) m.normals.push_back(float(v[at[c]]));
        if (hasQ) m.quality.push_back(float(v[at["quality"]]));
        if (hasC) m.colors.push_back({int(v[at["red"]]), int(v[at["green"]]), int(v[at["blue"]])});
    }
    for (size_t i = 0; i < nf; ++i) {
        int c;
        in >> c;
        std::vector<std::uint32_t> f(c);
        for (auto& x : f) in >> x;
        for (int t = 1; t + 1 < c; ++t) m.tris.push_back({f[0], f[t], f[t + 1]});
    }
    if (!in) throw std::runtime_error(path + ": truncated");
    return m;
}

inline void writePly(const std::string& path, const Mesh& m)
{
    std::ofstream out(path);
    out << "ply\nformat ascii 1.0\nelement vertex " << m.n()
        << "\nproperty float x\nproperty float y\nproperty float z\n";
    if (!m.tris.empty()) out << "element face " << m.tris.size() << "\nproperty list uchar int vertex_indices\n";
    out << "end_header\n";
    char b[128];
    for (size_t i = 0; i < m.n(); ++i) {
        std::snprintf(b, sizeof b, "%.9g %.9g %.9g\n", m.xyz[3 * i], m.xyz[3 * i + 1], m.xyz[3 * i + 2]);
        out << b;
    }
    for (const Tri& t : m.tris) out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
    if (!out) throw std::runtime_error("cannot write " + path);
}

inline Mesh readObj(const std::string& path)
{
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot open " + path);
    Mesh m;
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream ls(line);
        std::string w;
        ls >> w;
        if (w == "v") {
            float x, y, z;
            ls >> x >> y >> z;
            m.xyz.insert(m.xyz.end(), {x, y, z});
        } else if (w == "f") {
            std::vector<std::uint32_t> f;
            std::string tok;
            while (ls >> tok) f.push_back(std::uint32_t(std::stoul(tok.substr(0, tok.find('/'))) - 1));
            for (size_t t = 1; t + 1 < f.size(); ++t) m.tris.push_back({f[0], f[t], f[t + 1]});
        }
    }
    return m;
}

}  // namespace plyio
