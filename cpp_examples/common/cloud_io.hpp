// Point clouds as the peers' own loaders give them: a PCD file through pcl::io::loadPCDFile
// (pcl::PointXYZ, 16 bytes a point: x, y, z, padding) or an OBJ mesh through
// OpenMesh::IO::read_mesh (a TriMesh with float points, 12 bytes a point). The cloud keeps the
// loader's buffer alive and describes it (pointer, count, stride) so that nbhd and FLANN read it
// in place.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace examples {

struct Cloud {
    std::string name;    // file name, or the generator's name
    std::string loader;  // what produced the buffer
    // The loader's buffer, read in place: point i is at (const char*)xyz + i * stride.
    const float* xyz = nullptr;
    std::size_t count = 0;
    std::size_t stride = 0;
    // The cloud PCL's KdTreeFLANN is given: the loaded cloud itself for a PCD file; for a mesh or
    // a generated cloud a pcl::PointCloud copy of the points (PCL's tree takes nothing else).
    pcl::PointCloud<pcl::PointXYZ>::Ptr pcl;
    // Owner of a non-PCL buffer (the OpenMesh mesh, or a generated array).
    std::shared_ptr<void> owner;
    // Indices of the points with three finite coordinates (all of them unless NaN holes).
    std::vector<std::uint32_t> finite;

    const float* point(std::size_t i) const {
        return reinterpret_cast<const float*>(reinterpret_cast<const char*>(xyz) + i * stride);
    }
    bool has_non_finite() const { return finite.size() != count; }
};

/// Loads `path` by its extension: .pcd with PCL, .obj (or any mesh format OpenMesh reads) with
/// OpenMesh. Throws std::runtime_error if the file cannot be read or holds no point.
Cloud load_cloud(const std::string& path);

/// A cloud over `points` (packed x, y, z floats), kept alive by the cloud, with a PCL copy.
Cloud make_cloud(std::string name, std::vector<float> points);

}  // namespace examples
