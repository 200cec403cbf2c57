// Every point-cloud file nbhd writes, loaded by PCL's own loaders and compared value by value
// with what nbhd wrote (issue 13, items 1-4):
//
//   pcl_loads_nbhd_files NBHD_CLI DATA_DIR WORK_DIR
//
// The nbhd command-line tool writes, from the repository's scans,
//   - normals and curvature of milk.pcd (PCD binary / ascii / binary_compressed, PLY binary /
//     ascii), loaded with pcl::io::loadPCDFile / loadPLYFile into pcl::PointNormal and
//     pcl::PointXYZ;
//   - the coloured office1.pcd converted to the same five files, loaded into
//     pcl::PointXYZRGB (PCD's packed float rgb, PLY's uchar red/green/blue);
// and, from the same data, an XYZ text reference (float32 values printed exactly), which this
// program parses itself. Every coordinate, normal, curvature and colour PCL loads must equal the
// reference bit for bit (NaN holes as NaN). A loader that "succeeds" with zeros because it found
// no matching field ("Failed to find match for field 'x'") fails here.
//
// Then the binary_compressed size: PCL's own writer (pcl::PCDWriter::writeBinaryCompressed) on
// the same clouds must not produce a smaller file than nbhd.
//
// Exit status 0 when everything matches, 1 otherwise.
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

int failures = 0;

void fail(const std::string& msg) {
    std::cerr << "FAIL: " << msg << "\n";
    ++failures;
}

// Runs a command; a non-zero exit is fatal.
void run(const std::string& cmd) {
    std::cout << "$ " << cmd << "\n";
    if (std::system(cmd.c_str()) != 0) {
        std::cerr << "command failed: " << cmd << "\n";
        std::exit(1);
    }
}

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

// An XYZ file written by nbhd: "# name name ..." then one point per line.
struct Table {
    std::vector<std::string> names;
    std::vector<std::vector<float>> rows;

    int col(const std::string& n) const {
        for (std::size_t i = 0; i < names.size(); ++i)
            if (names[i] == n) return static_cast<int>(i);
        std::cerr << "reference has no column " << n << "\n";
        std::exit(1);
    }
};

Table read_table(const fs::path& p) {
    Table t;
    std::ifstream in(p);
    std::string line;
    std::getline(in, line);
    // nbhd's header line: `//x y z ...` (CloudCompare's form; `# x y z ...` before)
    const std::size_t names_at = std::min(line.find_first_not_of("/#"), line.size());
    std::istringstream h(line.substr(names_at));
    for (std::string n; h >> n;) t.names.push_back(n);
    while (std::getline(in, line)) {
        if (line.empty()) continue;
        std::vector<float> row;
        std::istringstream s(line);
        for (std::string tok; s >> tok;) row.push_back(std::strtof(tok.c_str(), nullptr));
        t.rows.push_back(row);
    }
    return t;
}

bool same(float a, float b) {
    if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
    std::uint32_t x, y;
    std::memcpy(&x, &a, 4);
    std::memcpy(&y, &b, 4);
    return x == y;
}

// Compares `what` of every point with the reference columns; reports the first mismatch.
template <typename Get>
void compare(const std::string& file, const Table& ref, std::size_t n,
             const std::vector<std::string>& cols, Get get) {
    if (n != ref.rows.size()) {
        fail(file + ": PCL loaded " + std::to_string(n) + " points, nbhd wrote " +
             std::to_string(ref.rows.size()));
        return;
    }
    std::vector<int> idx;
    for (const auto& c : cols) idx.push_back(ref.col(c));
    std::size_t finite = 0;
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t k = 0; k < cols.size(); ++k) {
            float want = ref.rows[i][idx[k]];
            float got = get(i, k);
            if (!same(got, want)) {
                fail(file + ": point " + std::to_string(i) + " " + cols[k] + " = " +
                     std::to_string(got) + ", nbhd wrote " + std::to_string(want));
                return;
            }
            if (k == 0 && std::isfinite(want)) ++finite;
        }
    }
    if (finite == 0) fail(file + ": no finite value at all");
    std::cout << "ok   " << file << ": " << n << " points, " << cols.size()
              << " values each equal to nbhd's\n";
}

void check_xyz(const fs::path& p, const Table& ref) {
    pcl::PointCloud<pcl::PointXYZ> c;
    bool ply = p.extension() == ".ply";
    int r = ply ? pcl::io::loadPLYFile(p.string(), c) : pcl::io::loadPCDFile(p.string(), c);
    if (r != 0) return fail(p.string() + ": PCL could not load it as PointXYZ");
    compare(p.filename().string() + " (PointXYZ)", ref, c.size(), {"x", "y", "z"},
            [&](std::size_t i, std::size_t k) { return c[i].data[k]; });
}

void check_normals(const fs::path& p, const Table& ref) {
    check_xyz(p, ref);
    pcl::PointCloud<pcl::PointNormal> c;
    bool ply = p.extension() == ".ply";
    int r = ply ? pcl::io::loadPLYFile(p.string(), c) : pcl::io::loadPCDFile(p.string(), c);
    if (r != 0) return fail(p.string() + ": PCL could not load it as PointNormal");
    compare(p.filename().string() + " (PointNormal)", ref, c.size(),
            {"x", "y", "z", "nx", "ny", "nz", "curvature"}, [&](std::size_t i, std::size_t k) {
                const auto& q = c[i];
                return k < 3 ? q.data[k] : k < 6 ? q.normal[k - 3] : q.curvature;
            });
}

// The sensor pose PCL reads from the file's VIEWPOINT: at the origin, turned by `q`.
void check_viewpoint(const fs::path& p, const Eigen::Quaternionf& q) {
    pcl::PointCloud<pcl::PointXYZ> c;
    if (pcl::io::loadPCDFile(p.string(), c) != 0) return fail(p.string() + ": PCL could not load it");
    const auto& o = c.sensor_orientation_;
    if (c.sensor_origin_.head<3>().norm() != 0 || o.w() != q.w() || o.x() != q.x() ||
        o.y() != q.y() || o.z() != q.z())
        return fail(p.string() + ": PCL read another VIEWPOINT than the input's");
    std::cout << "ok   " << p.filename().string() << ": VIEWPOINT as the input's\n";
}

void check_colour(const fs::path& p, const Table& ref) {
    check_xyz(p, ref);
    pcl::PointCloud<pcl::PointXYZRGB> c;
    bool ply = p.extension() == ".ply";
    int r = ply ? pcl::io::loadPLYFile(p.string(), c) : pcl::io::loadPCDFile(p.string(), c);
    if (r != 0) return fail(p.string() + ": PCL could not load it as PointXYZRGB");
    compare(p.filename().string() + " (PointXYZRGB)", ref, c.size(),
            {"x", "y", "z", "red", "green", "blue"}, [&](std::size_t i, std::size_t k) {
                const auto& q = c[i];
                return k < 3 ? q.data[k] : static_cast<float>(k == 3 ? q.r : k == 4 ? q.g : q.b);
            });
}

// PCL's binary_compressed writer on the cloud nbhd wrote (all its fields, as PCL loads them).
void compare_compressed_size(const fs::path& nbhd_file, const fs::path& pcl_file) {
    pcl::PCLPointCloud2 c;
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    int version = 0;
    pcl::PCDReader reader;
    if (reader.read(nbhd_file.string(), c, origin, orientation, version) != 0)
        return fail(nbhd_file.string() + ": PCL could not read it");
    pcl::PCDWriter writer;
    if (writer.writeBinaryCompressed(pcl_file.string(), c, origin, orientation) != 0)
        return fail(pcl_file.string() + ": PCL could not write it");
    auto ours = fs::file_size(nbhd_file), theirs = fs::file_size(pcl_file);
    std::cout << (ours <= theirs ? "ok   " : "FAIL ") << "binary_compressed "
              << nbhd_file.filename().string() << ": nbhd " << ours << " bytes, PCL " << theirs
              << " bytes\n";
    if (ours > theirs) fail("nbhd's binary_compressed is larger than PCL's");
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 4) {
        std::cerr << "usage: pcl_loads_nbhd_files NBHD_CLI DATA_DIR WORK_DIR\n";
        return 2;
    }
    const std::string nbhd = std::string("'") + argv[1] + "' -q";
    const fs::path data = argv[2], work = argv[3];
    fs::create_directories(work);

    // Normals and curvature of milk.pcd; the reference is the same output as text.
    const fs::path milk = data / "pcl" / "milk.pcd";
    run(nbhd + " curvature " + q(milk) + " " + q(work / "milk_n.pcd") + " --orient none");
    run(nbhd + " convert " + q(work / "milk_n.pcd") + " " + q(work / "milk_n.xyz"));
    run(nbhd + " convert " + q(work / "milk_n.pcd") + " " + q(work / "milk_n_ascii.pcd") +
        " -e ascii");
    run(nbhd + " convert " + q(work / "milk_n.pcd") + " " + q(work / "milk_n_comp.pcd") +
        " -e compressed");
    run(nbhd + " normals " + q(milk) + " " + q(work / "milk_n.ply") + " --orient none");
    run(nbhd + " convert " + q(work / "milk_n.ply") + " " + q(work / "milk_n_ascii.ply") +
        " -e ascii");
    const Table milk_ref = read_table(work / "milk_n.xyz");
    for (auto f : {"milk_n.pcd", "milk_n_ascii.pcd", "milk_n_comp.pcd", "milk_n.ply",
                   "milk_n_ascii.ply"})
        check_normals(work / f, milk_ref);

    // Colours of office1.pcd (an organized scan with NaN holes).
    const fs::path office = data / "pcl" / "office1.pcd";
    run(nbhd + " convert " + q(office) + " " + q(work / "office.xyz"));
    for (auto [f, enc] : std::vector<std::pair<std::string, std::string>>{
             {"office.pcd", ""},
             {"office_ascii.pcd", " -e ascii"},
             {"office_comp.pcd", " -e compressed"},
             {"office.ply", ""},
             {"office_ascii.ply", " -e ascii"}})
        run(nbhd + " convert " + q(office) + " " + q(work / f) + enc);
    const Table office_ref = read_table(work / "office.xyz");
    for (auto f : {"office.pcd", "office_ascii.pcd", "office_comp.pcd", "office.ply",
                   "office_ascii.ply"})
        check_colour(work / f, office_ref);
    // office1.pcd's VIEWPOINT 0 0 0 0 1 0 0 (a half turn about x) comes back in nbhd's PCD.
    for (auto f : {"office.pcd", "office_ascii.pcd", "office_comp.pcd"})
        check_viewpoint(work / f, Eigen::Quaternionf(0, 1, 0, 0));

    // binary_compressed against PCL's writer on the same clouds.
    compare_compressed_size(work / "office_comp.pcd", work / "office_comp_by_pcl.pcd");
    compare_compressed_size(work / "milk_n_comp.pcd", work / "milk_n_comp_by_pcl.pcd");

    if (failures) {
        std::cerr << failures << " check(s) failed\n";
        return 1;
    }
    std::cout << "all files nbhd writes load in PCL with nbhd's values\n";
    return 0;
}
