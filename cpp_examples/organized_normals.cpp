// Normals of an organized scan with NaN holes, written by nbhd straight into PCL's own point
// types, checked against PCL: the scan is loaded with pcl::io::loadPCDFile (not nbhd's reader),
// nbhd_estimate_normals (NBHD_NON_FINITE_POLICY_SKIP, oriented toward the sensor at the origin
// as pcl::NormalEstimation does) fills a pcl::PointCloud<pcl::Normal> and a
// pcl::PointCloud<pcl::PointNormal> in place, and the result is compared with
// pcl::NormalEstimation over the same neighbourhoods (the 15 nearest other points; PCL's k
// counts the point itself, so 16). Every hole must keep its index and get a NaN normal and
// curvature; the others must agree with PCL. nbhd_smooth then smooths the PointXYZ cloud in
// place: the holes stay NaN.
//
//   organized_normals SCAN.pcd
//
// Exits 0 when every check passed.
#include <nbhd.h>

#include <pcl/features/normal_3d.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

static int failures = 0;
#define CHECK(cond, ...)                                                                           \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            std::fprintf(stderr, "check failed: %s: ", #cond);                                     \
            std::fprintf(stderr, __VA_ARGS__);                                                     \
            std::fprintf(stderr, "\n");                                                            \
            failures++;                                                                            \
        }                                                                                          \
    } while (0)

int main(int argc, char **argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: organized_normals SCAN.pcd\n");
        return 2;
    }
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    if (pcl::io::loadPCDFile<pcl::PointXYZ>(argv[1], *cloud) != 0) return 2;
    const std::size_t n = cloud->size();
    std::size_t holes = 0;
    for (const auto &p : cloud->points) holes += !pcl::isFinite(p);
    std::printf("%s: %zu points (%u x %u), %zu NaN holes\n", argv[1], n, cloud->width,
                cloud->height, holes);
    CHECK(cloud->height > 1 && holes > 0, "an organized scan with holes");

    nbhd_points pts = {cloud->points.data(), n, 3, sizeof(pcl::PointXYZ), NBHD_SCALAR_TYPE_F32};
    nbhd_normal_options no = nbhd_normal_options_default();
    no.k = 15;
    no.epsilon = 1e9; // no radius cut, as PCL's k search
    no.epsilon_units = NBHD_UNITS_ABSOLUTE;
    no.orientation = NBHD_ORIENTATION_TOWARD_POINT; // PCL's default viewpoint: the origin
    // Rejected by default, as nbhd_tree_build does; skipped on request.
    pcl::PointCloud<pcl::Normal> normals;
    normals.resize(n);
    nbhd_normals_output out = {&normals[0].normal_x, sizeof(pcl::Normal), NBHD_SCALAR_TYPE_F32,
                               &normals[0].curvature, sizeof(pcl::Normal), nullptr};
    CHECK(nbhd_estimate_normals(&pts, &no, &out) == NBHD_STATUS_NON_FINITE, "reject");
    no.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
    nbhd_status st = nbhd_estimate_normals(&pts, &no, &out);
    CHECK(st == NBHD_STATUS_OK, "%s", nbhd_last_error_message());

    // The same into PointNormal records (x y z, normal, curvature in one struct).
    pcl::PointCloud<pcl::PointNormal> pn;
    pcl::copyPointCloud(*cloud, pn);
    nbhd_normals_output out2 = {&pn[0].normal_x, sizeof(pcl::PointNormal), NBHD_SCALAR_TYPE_F32,
                                &pn[0].curvature, sizeof(pcl::PointNormal), nullptr};
    CHECK(nbhd_estimate_normals(&pts, &no, &out2) == NBHD_STATUS_OK, "%s",
          nbhd_last_error_message());

    // PCL over the same neighbourhoods.
    pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
    ne.setInputCloud(cloud);
    ne.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(new pcl::search::KdTree<pcl::PointXYZ>));
    ne.setKSearch(16);
    pcl::PointCloud<pcl::Normal> ref;
    ne.compute(ref);

    std::size_t agree = 0, compared = 0, nan_ok = 0;
    std::vector<double> dcurv;
    for (std::size_t i = 0; i < n; ++i) {
        const auto &a = normals[i];
        const auto &b = pn[i];
        if (!pcl::isFinite((*cloud)[i])) {
            nan_ok += std::isnan(a.normal_x) && std::isnan(a.curvature) && std::isnan(b.normal_x);
            continue;
        }
        CHECK(a.normal_x == b.normal_x && a.normal_y == b.normal_y && a.normal_z == b.normal_z &&
                  a.curvature == b.curvature && b.x == (*cloud)[i].x,
              "Normal and PointNormal outputs differ at %zu", i);
        const double len = std::sqrt(double(a.normal_x) * a.normal_x + double(a.normal_y) * a.normal_y +
                                     double(a.normal_z) * a.normal_z);
        CHECK(std::fabs(len - 1.0) < 1e-5, "unit normal at %zu", i);
        const auto &r = ref[i];
        if (!std::isfinite(r.normal_x)) continue;
        compared++;
        const double dot = double(a.normal_x) * r.normal_x + double(a.normal_y) * r.normal_y +
                           double(a.normal_z) * r.normal_z;
        agree += dot > 0.999; // the same direction and, toward the viewpoint, the same sign
        dcurv.push_back(std::fabs(double(a.curvature) - r.curvature));
    }
    std::sort(dcurv.begin(), dcurv.end());
    const double med = dcurv.empty() ? 1.0 : dcurv[dcurv.size() / 2];
    std::printf("holes with NaN normal and curvature: %zu of %zu; normals within 2.6 deg of PCL's "
                "(same sign): %zu of %zu; median |curvature - PCL's| %.2e\n",
                nan_ok, holes, agree, compared, med);
    CHECK(nan_ok == holes, "every hole NaN");
    CHECK(compared > 0 && agree >= compared * 99 / 100, "99%% agree with PCL");
    CHECK(med < 1e-4, "curvature is PCL's surface variation");

    // Smoothing in place on the PointXYZ cloud: the holes stay NaN.
    nbhd_smooth_options so = nbhd_smooth_options_default();
    so.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
    st = nbhd_smooth(&pts, &so, cloud->points.data(), nullptr, nullptr);
    CHECK(st == NBHD_STATUS_OK, "%s", nbhd_last_error_message());
    std::size_t still = 0;
    for (const auto &p : cloud->points) still += !pcl::isFinite(p);
    CHECK(still == holes, "holes unmoved after smoothing: %zu of %zu", still, holes);

    std::printf("%s\n", failures ? "FAILED" : "ok");
    return failures ? 1 : 0;
}
