/* Uses nbhd from C, linked as the package says: built against nbhd::nbhd (shared), against
 * nbhd::nbhd_static (libnbhd.a plus the system libraries the package declares: proves that list
 * complete) and, by scripts/cpp-test.sh, with the pkg-config files. Also proves the header valid C. Builds a tree over 8 cube corners stored with a 16-byte stride and checks a table
 * row and a radius query against values known by construction. */
#include <nbhd.h>

#include <stdio.h>
#include <string.h>

static int fail(const char* what, nbhd_status s) {
    fprintf(stderr, "link_check: %s: %s (%s)\n", what, nbhd_status_string(s), nbhd_last_error_message());
    return 1;
}

int main(void) {
    if (nbhd_version() != NBHD_VERSION) {
        fprintf(stderr, "link_check: header %d, library %s\n", NBHD_VERSION, nbhd_version_string());
        return 1;
    }
    /* corners of the unit cube, x y z and a padding float as in pcl::PointXYZ; index = 4x+2y+z */
    float pts[8][4];
    for (int i = 0; i < 8; ++i) {
        pts[i][0] = (float)((i >> 2) & 1);
        pts[i][1] = (float)((i >> 1) & 1);
        pts[i][2] = (float)(i & 1);
        pts[i][3] = 1e30f; /* never read */
    }
    nbhd_points p = {pts, 8, 3, sizeof pts[0], NBHD_SCALAR_TYPE_F32};
    nbhd_tree* tree = NULL;
    nbhd_status s = nbhd_tree_build(&p, NULL, &tree);
    if (s != NBHD_STATUS_OK) return fail("nbhd_tree_build", s);

    /* corner 0: three neighbours at distance 1 (indices 1, 2, 4, ordered by index) */
    nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_KNN, 3, 0.0};
    nbhd_neighborhoods* table = NULL;
    s = nbhd_tree_neighborhoods(tree, &spec, NULL, &table);
    if (s != NBHD_STATUS_OK) return fail("nbhd_tree_neighborhoods", s);
    const uint32_t* idx;
    const void* sq;
    size_t len;
    s = nbhd_neighborhoods_row(table, 0, &idx, &sq, &len);
    if (s != NBHD_STATUS_OK) return fail("nbhd_neighborhoods_row", s);
    const float* d = (const float*)sq;
    if (len != 3 || idx[0] != 1 || idx[1] != 2 || idx[2] != 4 || d[0] != 1.0f || d[2] != 1.0f) {
        fprintf(stderr, "link_check: row 0 is wrong (len %zu)\n", len);
        return 1;
    }
    /* radius 1 around corner 7 (1,1,1), inclusive: itself and the 3 corners at distance exactly 1
     * (a strict radius would keep only the corner itself) */
    uint32_t ri[8];
    float rd[8];
    size_t count = 0;
    float q[3] = {1.0f, 1.0f, 1.0f};
    s = nbhd_tree_radius(tree, q, 1.0, ri, rd, 8, &count);
    if (s != NBHD_STATUS_OK) return fail("nbhd_tree_radius", s);
    size_t expect = 4;
    if (count != expect || ri[0] != 7 || ri[1] != 3 || ri[2] != 5 || ri[3] != 6 || rd[3] != 1.0f) {
        fprintf(stderr, "link_check: radius query gave %zu points, expected %zu\n", count, expect);
        return 1;
    }
    nbhd_neighborhoods_free(table);
    nbhd_tree_free(tree);
    printf("link_check: nbhd %s: kNN table and radius query correct\n", nbhd_version_string());
    return 0;
}
