// The only translation unit that includes PCL's and OpenMesh's readers.
#include "cloud_io.hpp"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <pcl/io/pcd_io.h>

#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <utility>

namespace examples {
namespace {

using Mesh = OpenMesh::TriMesh_ArrayKernelT<>;  // points are OpenMesh::Vec3f
static_assert(sizeof(pcl::PointXYZ) == 16 && offsetof(pcl::PointXYZ, x) == 0,
              "pcl::PointXYZ is x, y, z and padding");
static_assert(sizeof(Mesh::Point) == 3 * sizeof(float), "a float TriMesh point is 3 packed floats");

std::string base_name(const std::string& path) {
    std::size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? path : path.substr(slash + 1);
}

bool ends_with(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

void collect_finite(Cloud& c) {
    c.finite.clear();
    for (std::size_t i = 0; i < c.count; ++i) {
        const float* p = c.point(i);
        if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))
            c.finite.push_back(static_cast<std::uint32_t>(i));
    }
}

pcl::PointCloud<pcl::PointXYZ>::Ptr pcl_copy(const Cloud& c) {
    auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    cloud->resize(c.count);
    for (std::size_t i = 0; i < c.count; ++i) {
        const float* p = c.point(i);
        (*cloud)[i] = pcl::PointXYZ(p[0], p[1], p[2]);
    }
    cloud->width = static_cast<std::uint32_t>(c.count);
    cloud->height = 1;
    cloud->is_dense = c.finite.size() == c.count;
    return cloud;
}

}  // namespace

Cloud load_cloud(const std::string& path) {
    Cloud c;
    c.name = base_name(path);
    if (ends_with(path, ".pcd")) {
        auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
        if (pcl::io::loadPCDFile<pcl::PointXYZ>(path, *cloud) != 0)
            throw std::runtime_error("pcl::io::loadPCDFile cannot read " + path);
        c.loader = "pcl::io::loadPCDFile<pcl::PointXYZ>";
        c.pcl = cloud;
        c.count = cloud->size();
        c.xyz = c.count ? &(*cloud)[0].x : nullptr;
        c.stride = sizeof(pcl::PointXYZ);
    } else {
        auto mesh = std::make_shared<Mesh>();
        if (!OpenMesh::IO::read_mesh(*mesh, path))
            throw std::runtime_error("OpenMesh::IO::read_mesh cannot read " + path);
        c.loader = "OpenMesh::IO::read_mesh (TriMesh, float points)";
        c.count = mesh->n_vertices();
        c.xyz = c.count ? mesh->points()[0].data() : nullptr;
        c.stride = sizeof(Mesh::Point);
        c.owner = mesh;
    }
    if (c.count == 0) throw std::runtime_error(path + " holds no point");
    collect_finite(c);
    if (!c.pcl) c.pcl = pcl_copy(c);
    return c;
}

Cloud make_cloud(std::string name, std::vector<float> points) {
    auto owned = std::make_shared<std::vector<float>>(std::move(points));
    Cloud c;
    c.name = std::move(name);
    c.loader = "generated";
    c.count = owned->size() / 3;
    c.xyz = owned->data();
    c.stride = 3 * sizeof(float);
    c.owner = owned;
    collect_finite(c);
    c.pcl = pcl_copy(c);
    return c;
}

}  // namespace examples
