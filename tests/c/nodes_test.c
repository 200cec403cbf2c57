/*
 * The tree's nodes from C (nbhd_tree_nodes, nbhd_tree_order, nbhd_tree_node_weights) against
 * facts computed here from the points: in every pivot policy, f32 and f64, on points with
 * duplicates, a NaN point skipped and small leaves, the list is in preorder (left child right
 * after its parent, right child after the left subtree), children one level down, node ranges
 * nest and the root covers the tree order, which is a permutation of the finite points; each
 * node's points lie on their side of every split above them; weight sums equal sums over the
 * node's points computed here (bit for bit: leaves in tree order, internal nodes as left plus
 * right). Also the tree of no point, size queries, too-small buffers and every error's status.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "check.h"

#define N 97
#define DIM 3
#define LEAF 3

static double pts[N * DIM];
static float ptsf[N * DIM];
static double weights[N];

static void make_points(void) {
    uint64_t s = 777;
    size_t i;
    for (i = 0; i < N * DIM; i++) {
        s = s * 6364136223846793005ULL + 1442695040888963407ULL;
        /* a coarse grid: many equal coordinates and some identical points */
        pts[i] = (double)((s >> 33) % 5) * 0.25;
        ptsf[i] = (float)pts[i];
    }
    pts[10 * DIM + 1] = NAN; /* skipped */
    ptsf[10 * DIM + 1] = NAN;
    for (i = 0; i < N; i++) weights[i] = (double)(i % 7) - 2.5;
}

static double coord(int f32, uint32_t i, size_t j) {
    return f32 ? (double)ptsf[i * DIM + j] : pts[i * DIM + j];
}

/* Checks the nodes below `at` (inclusive) and returns the position after its subtree:
 * preorder, levels, nesting ranges and the sides of `at`'s split for each child's points. */
static size_t check_subtree(const nbhd_node *nodes, size_t count, size_t at, size_t level,
                            const uint32_t *order, int f32, int *bad) {
    const nbhd_node *n = &nodes[at];
    size_t p, after;
    if (at >= count || n->level != level || n->start > n->end) {
        *bad = 1;
        return count;
    }
    if (n->leaf) {
        if (n->left != 0 || n->right != 0 || n->end - n->start > LEAF) *bad = 1;
        return at + 1;
    }
    if (n->left != at + 1 || n->split_dim >= DIM) *bad = 1;
    after = check_subtree(nodes, count, at + 1, level + 1, order, f32, bad);
    if (n->right != after) *bad = 1;
    after = check_subtree(nodes, count, n->right, level + 1, order, f32, bad);
    if (*bad) return count;
    if (nodes[n->left].start != n->start || nodes[n->left].end != nodes[n->right].start ||
        nodes[n->right].end != n->end)
        *bad = 1;
    for (p = n->start; p < n->end; p++) {
        double x = coord(f32, order[p], n->split_dim);
        if (p < nodes[n->right].start ? x > n->split : x < n->split) *bad = 1;
    }
    return after;
}

static void test_nodes(void) {
    static const nbhd_pivot_policy pivots[4] = {
        NBHD_PIVOT_POLICY_CYCLIC_MEDIAN, NBHD_PIVOT_POLICY_SPREAD_MEDIAN,
        NBHD_PIVOT_POLICY_CLOSEST_TO_MIDDLE, NBHD_PIVOT_POLICY_SLIDING_MIDPOINT};
    int pv, f32;
    for (pv = 0; pv < 4; pv++) {
        for (f32 = 0; f32 < 2; f32++) {
            nbhd_build_options o = nbhd_build_options_default();
            nbhd_points p = {f32 ? (const void *)ptsf : (const void *)pts, N, DIM,
                             DIM * (f32 ? sizeof(float) : sizeof(double)),
                             f32 ? NBHD_SCALAR_TYPE_F32 : NBHD_SCALAR_TYPE_F64};
            nbhd_tree *tree = NULL;
            nbhd_stats st;
            nbhd_node *nodes;
            double *sums;
            uint32_t order[N];
            unsigned char seen[N] = {0};
            size_t count = 99, i, p2;
            int bad = 0;
            o.pivot = pivots[pv];
            o.leaf_size = LEAF;
            o.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
            CHECK_STATUS(nbhd_tree_build(&p, &o, &tree), NBHD_STATUS_OK);
            CHECK_STATUS(nbhd_tree_stats(tree, &st), NBHD_STATUS_OK);
            CHECK(st.points == N - 1 && st.nodes > 1);

            /* sizes: a NULL buffer of capacity 0 asks for them */
            CHECK_STATUS(nbhd_tree_nodes(tree, NULL, 0, &count), NBHD_STATUS_BUFFER_TOO_SMALL);
            CHECK(count == st.nodes);
            CHECK_STATUS(nbhd_tree_order(tree, NULL, 0, &count), NBHD_STATUS_BUFFER_TOO_SMALL);
            CHECK(count == N - 1);
            nodes = malloc(st.nodes * sizeof *nodes);
            sums = malloc(st.nodes * sizeof *sums);
            if (!nodes || !sums) abort();
            CHECK_STATUS(nbhd_tree_nodes(tree, nodes, st.nodes, &count), NBHD_STATUS_OK);
            CHECK(count == st.nodes);
            CHECK_STATUS(nbhd_tree_order(tree, order, N, &count), NBHD_STATUS_OK);
            CHECK(count == N - 1);

            /* the tree order: every finite point once, the NaN point absent */
            for (i = 0; i < N - 1; i++) {
                if (order[i] >= N || order[i] == 10 || seen[order[i]]) bad = 1;
                else seen[order[i]] = 1;
            }
            CHECK(!bad);
            CHECK(nodes[0].level == 0 && nodes[0].start == 0 && nodes[0].end == N - 1);
            CHECK(check_subtree(nodes, st.nodes, 0, 0, order, f32, &bad) == st.nodes);
            CHECK(!bad);

            /* weight sums against sums over each node's points (a leaf in tree order, an
             * internal node as left plus right: the library's order of additions) */
            CHECK_STATUS(nbhd_tree_node_weights(tree, weights, N, sums, st.nodes, &count),
                         NBHD_STATUS_OK);
            CHECK(count == st.nodes);
            for (i = st.nodes; i-- > 0;) {
                double s = 0.0, direct = 0.0;
                if (nodes[i].leaf)
                    for (p2 = nodes[i].start; p2 < nodes[i].end; p2++) s += weights[order[p2]];
                else
                    s = sums[nodes[i].left] + sums[nodes[i].right];
                for (p2 = nodes[i].start; p2 < nodes[i].end; p2++) direct += weights[order[p2]];
                /* the weights are multiples of 0.5: every sum is exact in any order */
                if (sums[i] != s || sums[i] != direct) bad = 1;
            }
            CHECK(!bad);
            free(nodes);
            free(sums);
            nbhd_tree_free(tree);
        }
    }
}

static void test_empty(void) {
    nbhd_points p = {NULL, 0, DIM, DIM * sizeof(double), NBHD_SCALAR_TYPE_F64};
    nbhd_tree *tree = NULL;
    nbhd_node node;
    double sum = 7.0;
    size_t count = 99;
    CHECK_STATUS(nbhd_tree_build(&p, NULL, &tree), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_nodes(tree, &node, 1, &count), NBHD_STATUS_OK);
    CHECK(count == 1 && node.leaf && node.start == 0 && node.end == 0 && node.level == 0);
    CHECK_STATUS(nbhd_tree_order(tree, NULL, 0, &count), NBHD_STATUS_OK);
    CHECK(count == 0);
    CHECK_STATUS(nbhd_tree_node_weights(tree, NULL, 0, &sum, 1, &count), NBHD_STATUS_OK);
    CHECK(count == 1 && sum == 0.0);
    nbhd_tree_free(tree);
}

static void test_errors(void) {
    nbhd_points p = {pts + 11 * DIM, 8, DIM, DIM * sizeof(double), NBHD_SCALAR_TYPE_F64};
    nbhd_build_options o = nbhd_build_options_default();
    nbhd_tree *tree = NULL;
    nbhd_node nodes[16];
    nbhd_node sentinel;
    uint32_t order[8];
    double sums[16], bad_w[8] = {1, 1, 1, 1, NAN, 1, 1, 1};
    size_t count = 99, n;
    o.leaf_size = 1;
    CHECK_STATUS(nbhd_tree_build(&p, &o, &tree), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_nodes(tree, nodes, 16, &count), NBHD_STATUS_OK);
    n = count;
    CHECK(n == 15); /* 8 points in leaves of one */

    /* too small: nothing written, the size needed in *count */
    memset(&sentinel, 0xAB, sizeof sentinel);
    nodes[0] = sentinel;
    CHECK_STATUS(nbhd_tree_nodes(tree, nodes, n - 1, &count), NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK(count == n && memcmp(&nodes[0], &sentinel, sizeof sentinel) == 0);
    CHECK_MESSAGE("nodes");
    order[0] = 12345;
    CHECK_STATUS(nbhd_tree_order(tree, order, 7, &count), NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK(count == 8 && order[0] == 12345);
    sums[0] = -1.0;
    CHECK_STATUS(nbhd_tree_node_weights(tree, weights, 8, sums, 3, &count),
                 NBHD_STATUS_BUFFER_TOO_SMALL);
    CHECK(count == n && sums[0] == -1.0);

    /* NULL pointers: named, *count 0 */
    CHECK_STATUS(nbhd_tree_nodes(NULL, nodes, 16, &count), NBHD_STATUS_NULL_POINTER);
    CHECK(count == 0);
    CHECK_MESSAGE("tree");
    CHECK_STATUS(nbhd_tree_nodes(tree, nodes, 16, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("count");
    count = 99;
    CHECK_STATUS(nbhd_tree_nodes(tree, NULL, 16, &count), NBHD_STATUS_NULL_POINTER);
    CHECK(count == 0);
    CHECK_MESSAGE("nodes");
    CHECK_STATUS(nbhd_tree_order(NULL, order, 8, &count), NBHD_STATUS_NULL_POINTER);
    CHECK(count == 0);
    CHECK_STATUS(nbhd_tree_order(tree, NULL, 8, &count), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_order(tree, order, 8, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_node_weights(NULL, weights, 8, sums, 16, &count),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_node_weights(tree, NULL, 8, sums, 16, &count),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("weights");
    CHECK_STATUS(nbhd_tree_node_weights(tree, weights, 8, NULL, 16, &count),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("sums");
    CHECK_STATUS(nbhd_tree_node_weights(tree, weights, 8, sums, 16, NULL),
                 NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_tree_nodes(tree, (nbhd_node *)((char *)nodes + 1), 16, &count),
                 NBHD_STATUS_MISALIGNED_POINTER);

    /* weights: one finite value per point */
    count = 99;
    CHECK_STATUS(nbhd_tree_node_weights(tree, weights, 7, sums, 16, &count),
                 NBHD_STATUS_INVALID_OPTION);
    CHECK(count == 0);
    CHECK_MESSAGE("7 weights for 8 points");
    CHECK_STATUS(nbhd_tree_node_weights(tree, bad_w, 8, sums, 16, &count),
                 NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("point 4");
    CHECK_STATUS(nbhd_tree_node_weights(tree, weights, SIZE_MAX, sums, 16, &count),
                 NBHD_STATUS_INVALID_ARGUMENT);
    nbhd_tree_free(tree);
}

int main(void) {
    make_points();
    test_nodes();
    test_empty();
    test_errors();
    printf("nodes_test: %d checks, %d failures\n", checks, failures);
    return failures == 0 ? 0 : 1;
}
