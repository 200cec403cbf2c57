/*
 * Normals, curvatures and smoothing through the C ABI, checked against the analytic truth of a
 * sphere: normals parallel to the radius, mean curvature 1/R, smoothing that brings noisy
 * points back toward the sphere. Also: in-place smoothing of a PCL-like strided float cloud,
 * progress and cancellation, identical results for 1 and 2 threads, the robust mode, and every
 * error path.
 * Run by tests/c_abi.rs (also under valgrind, with fewer points: argv[1]).
 */
#include "nbhd.h"
#include "check.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define R 2.0
#define PI 3.14159265358979323846

static uint64_t rng_state = 0x9E3779B97F4A7C15ULL;

static double uniform01(void) {
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* n points spread evenly on the sphere of radius R (a Fibonacci lattice), each moved along
 * its radius by up to `noise` (uniform). */
static void sphere(double *p, size_t n, double noise) {
    size_t i;
    const double golden = PI * (3.0 - sqrt(5.0));
    for (i = 0; i < n; i++) {
        double z = 1.0 - 2.0 * ((double)i + 0.5) / (double)n;
        double r = sqrt(1.0 - z * z), t = golden * (double)i;
        double len = R + noise * (2.0 * uniform01() - 1.0);
        p[3 * i] = len * r * cos(t);
        p[3 * i + 1] = len * r * sin(t);
        p[3 * i + 2] = len * z;
    }
}

/* Spread of the radii |p| about their mean over n packed double points: the noise that
 * smoothing removes, apart from the shrinkage (the change of the mean radius) that isotropic
 * fairing of a closed surface also causes. */
static double radial_spread(const double *p, size_t n, double *mean_radius) {
    size_t i;
    double s = 0.0, s2 = 0.0;
    for (i = 0; i < n; i++) {
        double r = sqrt(p[3 * i] * p[3 * i] + p[3 * i + 1] * p[3 * i + 1] + p[3 * i + 2] * p[3 * i + 2]);
        s += r;
        s2 += r * r;
    }
    *mean_radius = s / (double)n;
    return sqrt(fmax(s2 / (double)n - *mean_radius * *mean_radius, 0.0));
}

/* The mean spacing of n points evenly spread on the sphere. */
static double spacing(size_t n) {
    return sqrt(4.0 * PI * R * R / (double)n);
}

static nbhd_points describe(const void *data, size_t n, size_t stride, nbhd_scalar_type type) {
    nbhd_points p;
    p.data = data;
    p.count = n;
    p.dim = 3;
    p.stride = stride;
    p.scalar_type = type;
    return p;
}

/* Normals packed as double[3 * n] (and flags, may be NULL), no curvature. */
static nbhd_normals_output packed_normals(double *normals, uint8_t *flags) {
    nbhd_normals_output out;
    memset(&out, 0, sizeof out);
    out.normals = normals;
    out.normals_stride = 0;
    out.scalar_type = NBHD_SCALAR_TYPE_F64;
    out.curvature = NULL;
    out.flags = flags;
    return out;
}

static void test_defaults(void) {
    nbhd_smooth_options o = nbhd_smooth_options_default();
    CHECK(o.k == 15);
    CHECK(o.epsilon == 6.0 && o.epsilon_units == NBHD_UNITS_RELATIVE);
    CHECK(o.steps == 3 && o.tau == 0.5);
    CHECK(o.weighting == NBHD_WEIGHTING_SHARP);
    CHECK(o.lambda == 0.2 && o.lambda_units == NBHD_UNITS_RELATIVE);
    CHECK(o.feature == NBHD_FEATURE_CRITERION_ALL_POINTS);
    CHECK(!o.constrain_interior && !o.update_neighbors);
    CHECK(o.orientation == NBHD_ORIENTATION_UNORIENTED);
    CHECK(o.threads == 0 && o.progress == NULL && o.progress_user_data == NULL);
}

static void test_normals_and_curvatures(size_t n) {
    double *p = malloc(3 * n * sizeof *p);
    double *normals = malloc(3 * n * sizeof *normals);
    uint8_t *flags = malloc(n);
    nbhd_point_geometry *geo = malloc(n * sizeof *geo);
    nbhd_smooth_summary summary;
    nbhd_smooth_options o = nbhd_smooth_options_default();
    nbhd_points pts;
    size_t i, outward = 0, flagged = 0;
    double worst_cos = 1.0, mean_h = 0.0, mean_kmax = 0.0;

    sphere(p, n, 0.0);
    pts = describe(p, n, 0, NBHD_SCALAR_TYPE_F64);
    o.orientation = NBHD_ORIENTATION_AWAY_FROM_POINT;
    o.orientation_point[0] = o.orientation_point[1] = o.orientation_point[2] = 0.0;
    {
        nbhd_normal_options no = nbhd_normal_options_default();
        nbhd_normals_output out = packed_normals(normals, flags);
        no.orientation = o.orientation;
        CHECK_STATUS(nbhd_estimate_normals(&pts, &no, &out), NBHD_STATUS_OK);
    }
    for (i = 0; i < n; i++) {
        const double *q = p + 3 * i, *m = normals + 3 * i;
        double len = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        double c = (m[0] * q[0] + m[1] * q[1] + m[2] * q[2]) / R;
        CHECK(fabs(len - 1.0) < 1e-9);
        if (c < worst_cos) worst_cos = c;
        outward += c > 0.0;
        flagged += flags[i] != 0;
    }
    /* Away from the centre: every normal points outward, within 3 degrees of the radius. */
    CHECK(outward == n);
    CHECK(worst_cos > cos(3.0 * PI / 180.0));
    CHECK(flagged == 0);

    CHECK_STATUS(nbhd_estimate_curvatures(&pts, &o, geo, &summary), NBHD_STATUS_OK);
    for (i = 0; i < n; i++) {
        mean_h += geo[i].mean_curvature;
        mean_kmax += geo[i].max_principal_curvature;
        CHECK(geo[i].normal[0] == normals[3 * i] && geo[i].normal[2] == normals[3 * i + 2]);
        CHECK(geo[i].principal_curvature_quotient >= 0.0 && geo[i].principal_curvature_quotient <= 1.0);
        CHECK(geo[i].covariance_quotient >= 0.0 && geo[i].covariance_quotient <= 1.0 / 3.0 + 1e-12);
    }
    mean_h /= (double)n;
    mean_kmax /= (double)n;
    /* Outward normals on a sphere: the surface bends away from the normal, so the signed mean
     * curvature is -1/R; its magnitude within 5 %. */
    CHECK(fabs(fabs(mean_h) - 1.0 / R) < 0.05 / R);
    CHECK(mean_kmax >= fabs(mean_h));
    CHECK(summary.spacing > 0.0 && summary.min_neighbors >= 3);
    CHECK(fabs(summary.epsilon - 6.0 * summary.spacing) < 1e-12 * summary.epsilon);
    CHECK(fabs(summary.lambda - 0.2 / summary.spacing) < 1e-12 * summary.lambda);
    free(p);
    free(normals);
    free(flags);
    free(geo);
}

typedef struct {
    int calls;
    double last;
    int monotone;
    int saw_done;
    double stop_after; /* return false once the fraction exceeds this */
} progress_log;

static bool on_progress(double fraction, nbhd_stage stage, void *user_data) {
    progress_log *log = user_data;
    log->calls++;
    if (fraction < log->last || fraction < 0.0 || fraction > 1.0) log->monotone = 0;
    log->last = fraction;
    if (stage == NBHD_STAGE_DONE) log->saw_done = fraction == 1.0;
    return fraction <= log->stop_after;
}

/* Isotropic smoothing of a noisy sphere given as a PCL-like cloud: x y z and a fourth float,
 * 16 bytes apart, smoothed in place. */
static void test_smooth_in_place(size_t n) {
    double *p = malloc(3 * n * sizeof *p);
    float *cloud = malloc(4 * n * sizeof *cloud);
    float *copy = malloc(4 * n * sizeof *copy);
    double *back = malloc(3 * n * sizeof *back);
    nbhd_smooth_options o = nbhd_smooth_options_default();
    progress_log log = {0, 0.0, 1, 0, 2.0};
    nbhd_points pts;
    size_t i;
    double before, after, r_before, r_after;
    int padding_kept = 1;

    sphere(p, n, 0.5 * spacing(n));
    for (i = 0; i < n; i++) {
        cloud[4 * i] = (float)p[3 * i];
        cloud[4 * i + 1] = (float)p[3 * i + 1];
        cloud[4 * i + 2] = (float)p[3 * i + 2];
        cloud[4 * i + 3] = (float)i; /* PCL's padding: must survive */
        back[3 * i] = cloud[4 * i];
        back[3 * i + 1] = cloud[4 * i + 1];
        back[3 * i + 2] = cloud[4 * i + 2];
    }
    before = radial_spread(back, n, &r_before);
    memcpy(copy, cloud, 4 * n * sizeof *cloud);
    pts = describe(cloud, n, 16, NBHD_SCALAR_TYPE_F32);
    o.weighting = NBHD_WEIGHTING_ISOTROPIC;
    o.steps = 2;
    o.progress = on_progress;
    o.progress_user_data = &log;

    /* Cancelled half-way: the status says so and the cloud is untouched. */
    log.stop_after = 0.5;
    CHECK_STATUS(nbhd_smooth(&pts, &o, cloud, NULL, NULL), NBHD_STATUS_CANCELLED);
    CHECK(memcmp(copy, cloud, 4 * n * sizeof *cloud) == 0);

    log = (progress_log){0, 0.0, 1, 0, 2.0};
    CHECK_STATUS(nbhd_smooth(&pts, &o, cloud, NULL, NULL), NBHD_STATUS_OK);
    CHECK(log.calls >= 4 && log.monotone && log.saw_done);
    for (i = 0; i < n; i++) {
        padding_kept &= cloud[4 * i + 3] == (float)i;
        back[3 * i] = cloud[4 * i];
        back[3 * i + 1] = cloud[4 * i + 1];
        back[3 * i + 2] = cloud[4 * i + 2];
    }
    after = radial_spread(back, n, &r_after);
    CHECK(padding_kept);
    /* Uniform radial noise of half a spacing (RMS 0.29 spacings): two isotropic steps remove
     * most of it, and shrink the sphere by less than half a spacing. */
    CHECK(after < 0.5 * before);
    CHECK(r_after < R && R - r_after < 0.5 * spacing(n));
    if (!(after < 0.5 * before) || !(R - r_after < 0.5 * spacing(n)))
        fprintf(stderr, "radial spread before %g after %g; mean radius %g -> %g (h = %g)\n", before,
                after, r_before, r_after, spacing(n));
    free(p);
    free(cloud);
    free(copy);
    free(back);
}

/* The anisotropic default on 1 and on 2 threads: the same bytes. */
static void test_threads_agree(size_t n) {
    double *p = malloc(3 * n * sizeof *p);
    double *a = malloc(3 * n * sizeof *a);
    double *b = malloc(3 * n * sizeof *b);
    nbhd_point_geometry *ga = malloc(n * sizeof *ga);
    nbhd_point_geometry *gb = malloc(n * sizeof *gb);
    nbhd_smooth_options o = nbhd_smooth_options_default();
    nbhd_points pts;
    size_t i;
    int same = 1;

    sphere(p, n, 0.5 * spacing(n));
    pts = describe(p, n, 3 * sizeof(double), NBHD_SCALAR_TYPE_F64);
    o.threads = 1;
    CHECK_STATUS(nbhd_smooth(&pts, &o, a, ga, NULL), NBHD_STATUS_OK);
    o.threads = 2;
    CHECK_STATUS(nbhd_smooth(&pts, &o, b, gb, NULL), NBHD_STATUS_OK);
    CHECK(memcmp(a, b, 3 * n * sizeof *a) == 0);
    for (i = 0; i < n; i++) {
        same &= memcmp(ga[i].normal, gb[i].normal, sizeof ga[i].normal) == 0;
        same &= ga[i].k1 == gb[i].k1 && ga[i].k2 == gb[i].k2 && ga[i].feature == gb[i].feature;
    }
    CHECK(same);
    free(p);
    free(a);
    free(b);
    free(ga);
    free(gb);
}

/* The robust mode on the noisy sphere: noise removed, and (unlike isotropic fairing) almost no
 * shrinkage; bad options named. */
static void test_robust(size_t n) {
    double *p = malloc(3 * n * sizeof *p);
    double *out = malloc(3 * n * sizeof *out);
    double *out2 = malloc(3 * n * sizeof *out2);
    nbhd_robust_options o = nbhd_robust_options_default();
    nbhd_smooth_summary summary;
    nbhd_points pts;
    double before, after, r_before, r_after;

    CHECK(o.k == 24 && o.k_plane == 48 && o.epsilon == 12.0 && o.epsilon_units == NBHD_UNITS_RELATIVE);
    CHECK(o.max_iterations == 10 && o.tau == 1.0 && o.progress == NULL && o.threads == 0);
    CHECK(o.noise_scale);

    sphere(p, n, 0.5 * spacing(n));
    pts = describe(p, n, 0, NBHD_SCALAR_TYPE_F64);
    before = radial_spread(p, n, &r_before);
    CHECK_STATUS(nbhd_smooth_robust(&pts, NULL, out, NULL, &summary), NBHD_STATUS_OK);
    after = radial_spread(out, n, &r_after);
    CHECK(after < 0.5 * before);
    CHECK(fabs(r_after - r_before) < 0.1 * spacing(n));
    if (!(after < 0.5 * before) || !(fabs(r_after - r_before) < 0.1 * spacing(n)))
        fprintf(stderr, "robust: radial spread %g -> %g, mean radius %g -> %g (h = %g)\n", before, after,
                r_before, r_after, spacing(n));
    CHECK(summary.spacing > 0.0 && summary.lambda > 0.0);

    /* noise of half a spacing is no ball of noise: the noise scale leaves it as without it */
    o.noise_scale = false;
    CHECK_STATUS(nbhd_smooth_robust(&pts, &o, out2, NULL, NULL), NBHD_STATUS_OK);
    CHECK(memcmp(out, out2, 3 * n * sizeof *out) == 0);

    o = nbhd_robust_options_default();
    o.k_plane = 10;
    CHECK_STATUS(nbhd_smooth_robust(&pts, &o, out, NULL, NULL), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("k_plane");
    o = nbhd_robust_options_default();
    o.tau = 1.5;
    CHECK_STATUS(nbhd_smooth_robust(&pts, &o, out, NULL, NULL), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("tau");
    CHECK_STATUS(nbhd_smooth_robust(&pts, NULL, NULL, NULL, NULL), NBHD_STATUS_NULL_POINTER);
    free(p);
    free(out);
    free(out2);
}

static void test_errors(void) {
    double p[3 * 40], out[3 * 40];
    double flat2[2 * 40];
    uint8_t flags[40];
    nbhd_point_geometry geo[40];
    nbhd_smooth_options o;
    nbhd_normal_options no;
    nbhd_normals_output nout;
    nbhd_points pts;
    size_t i;

    sphere(p, 40, 0.0);
    memset(flat2, 0, sizeof flat2);
    pts = describe(p, 40, 0, NBHD_SCALAR_TYPE_F64);

    CHECK_STATUS(nbhd_smooth(NULL, NULL, out, NULL, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("points");
    CHECK_STATUS(nbhd_smooth(&pts, NULL, NULL, NULL, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("out_coords");
    CHECK_STATUS(nbhd_estimate_normals(&pts, NULL, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("out");
    nout = packed_normals(NULL, flags);
    CHECK_STATUS(nbhd_estimate_normals(&pts, NULL, &nout), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("out->normals");
    nout = packed_normals(out, NULL);
    nout.normals_stride = 16; /* less than 3 doubles */
    CHECK_STATUS(nbhd_estimate_normals(&pts, NULL, &nout), NBHD_STATUS_INVALID_ARGUMENT);
    CHECK_MESSAGE("normals_stride 16");
    nout = packed_normals(out, NULL);
    nout.normals_stride = SIZE_MAX / 8;
    CHECK_STATUS(nbhd_estimate_normals(&pts, NULL, &nout), NBHD_STATUS_INVALID_ARGUMENT);
    CHECK_MESSAGE("overflows");
    CHECK_STATUS(nbhd_estimate_curvatures(&pts, NULL, NULL, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("out_geometry");
    CHECK_STATUS(nbhd_estimate_curvatures(&pts, NULL, (nbhd_point_geometry *)((char *)geo + 1), NULL),
                 NBHD_STATUS_MISALIGNED_POINTER);

    /* Zero points, wrong dimension. */
    pts.count = 0;
    CHECK_STATUS(nbhd_smooth(&pts, NULL, out, NULL, NULL), NBHD_STATUS_EMPTY_INPUT);
    pts = describe(flat2, 40, 0, NBHD_SCALAR_TYPE_F64);
    pts.dim = 2;
    nout = packed_normals(out, NULL);
    CHECK_STATUS(nbhd_estimate_normals(&pts, NULL, &nout), NBHD_STATUS_INVALID_ARGUMENT);
    CHECK_MESSAGE("need 3-D points");

    /* A NaN coordinate: named by index. */
    pts = describe(p, 40, 0, NBHD_SCALAR_TYPE_F64);
    p[3 * 17 + 1] = NAN;
    CHECK_STATUS(nbhd_smooth(&pts, NULL, out, NULL, NULL), NBHD_STATUS_NON_FINITE);
    CHECK_MESSAGE("17");
    p[3 * 17 + 1] = INFINITY;
    CHECK_STATUS(nbhd_estimate_normals(&pts, NULL, &nout), NBHD_STATUS_NON_FINITE);
    sphere(p, 40, 0.0);

    /* Options out of range. */
    o = nbhd_smooth_options_default();
    o.k = 0;
    CHECK_STATUS(nbhd_smooth(&pts, &o, out, NULL, NULL), NBHD_STATUS_INVALID_K);
    o = nbhd_smooth_options_default();
    o.epsilon = -1.0;
    CHECK_STATUS(nbhd_smooth(&pts, &o, out, NULL, NULL), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("epsilon");
    o.epsilon = NAN;
    CHECK_STATUS(nbhd_smooth(&pts, &o, out, NULL, NULL), NBHD_STATUS_INVALID_OPTION);
    o = nbhd_smooth_options_default();
    o.tau = -0.5;
    CHECK_STATUS(nbhd_smooth(&pts, &o, out, NULL, NULL), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("tau");
    o = nbhd_smooth_options_default();
    o.lambda = 0.0;
    CHECK_STATUS(nbhd_smooth(&pts, &o, out, NULL, NULL), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("lambda");
    o = nbhd_smooth_options_default();
    {
        int bad = 7; /* C may store any int in an enum field: it must be refused, not trusted */
        memcpy(&o.weighting, &bad, sizeof bad);
    }
    /* an enum field of an options struct out of range is an option out of range */
    CHECK_STATUS(nbhd_smooth(&pts, &o, out, NULL, NULL), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("weighting");
    no = nbhd_normal_options_default();
    no.orientation = NBHD_ORIENTATION_TOWARD_POINT;
    no.orientation_point[1] = NAN;
    CHECK_STATUS(nbhd_estimate_normals(&pts, &no, &nout), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("orientation_point");

    /* All points identical: relative units have no spacing to refer to, and say so; with
     * absolute units every normal is degenerate, which is refused for the normals alone
     * (DEGENERATE) while smoothing leaves the points where they are. */
    for (i = 0; i < 40; i++) {
        p[3 * i] = 1.0;
        p[3 * i + 1] = 2.0;
        p[3 * i + 2] = 3.0;
    }
    CHECK_STATUS(nbhd_smooth(&pts, NULL, out, NULL, NULL), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("spacing");
    o = nbhd_smooth_options_default();
    o.epsilon = 1.0;
    o.epsilon_units = NBHD_UNITS_ABSOLUTE;
    o.lambda_units = NBHD_UNITS_ABSOLUTE;
    no = nbhd_normal_options_default();
    no.epsilon = 1.0;
    no.epsilon_units = NBHD_UNITS_ABSOLUTE;
    nout = packed_normals(out, flags);
    CHECK_STATUS(nbhd_estimate_normals(&pts, &no, &nout), NBHD_STATUS_DEGENERATE);
    CHECK_MESSAGE("all 40 of 40 normals are degenerate");
    CHECK_STATUS(nbhd_estimate_curvatures(&pts, &o, geo, NULL), NBHD_STATUS_DEGENERATE);
    CHECK_STATUS(nbhd_smooth(&pts, &o, out, geo, NULL), NBHD_STATUS_OK);
    for (i = 0; i < 40; i++) CHECK(geo[i].normal_flags != 0 && isfinite(geo[i].normal[0]));
    CHECK(out[0] == 1.0 && out[1] == 2.0 && out[2] == 3.0);
}

/* An organized scan's holes: NaN points with NBHD_NON_FINITE_POLICY_SKIP keep their index, are
 * left unmoved and get NaN geometry (flag 8); every other point gets exactly what the finite
 * points alone give. */
static void test_non_finite_skip(size_t n) {
    double *p = malloc(3 * n * sizeof *p), *fin = malloc(3 * n * sizeof *fin);
    double *out = malloc(3 * n * sizeof *out), *fout = malloc(3 * n * sizeof *fout);
    double *nrm = malloc(3 * n * sizeof *nrm), *fnrm = malloc(3 * n * sizeof *fnrm);
    uint8_t *flags = malloc(n), *fflags = malloc(n);
    nbhd_point_geometry *geo = malloc(n * sizeof *geo), *fgeo = malloc(n * sizeof *fgeo);
    nbhd_smooth_options o = nbhd_smooth_options_default();
    nbhd_robust_options ro = nbhd_robust_options_default();
    nbhd_normal_options no = nbhd_normal_options_default();
    nbhd_normals_output nout, fnout;
    nbhd_points pts, fpts;
    size_t i, m = 0, j;

    sphere(p, n, 0.05 * spacing(n));
    for (i = 0; i < n; i++) {
        if (i % 7 == 3) {
            p[3 * i] = NAN; /* a hole, as PCL marks them */
            p[3 * i + 1] = NAN;
            p[3 * i + 2] = NAN;
        } else {
            memcpy(fin + 3 * m, p + 3 * i, 3 * sizeof *p);
            m++;
        }
    }
    pts = describe(p, n, 0, NBHD_SCALAR_TYPE_F64);
    fpts = describe(fin, m, 0, NBHD_SCALAR_TYPE_F64);
    /* Rejected by default, as nbhd_tree_build does. */
    CHECK_STATUS(nbhd_smooth(&pts, &o, out, NULL, NULL), NBHD_STATUS_NON_FINITE);
    CHECK_MESSAGE("point 3 ");
    o.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
    ro.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
    no.non_finite = NBHD_NON_FINITE_POLICY_SKIP;
    nout = packed_normals(nrm, flags);
    fnout = packed_normals(fnrm, fflags);

    CHECK_STATUS(nbhd_smooth(&pts, &o, out, geo, NULL), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_smooth(&fpts, NULL, fout, fgeo, NULL), NBHD_STATUS_OK);
    for (i = 0, j = 0; i < n; i++) {
        if (i % 7 == 3) {
            CHECK(isnan(out[3 * i]) && isnan(out[3 * i + 1]) && isnan(out[3 * i + 2]));
            CHECK(isnan(geo[i].normal[0]) && isnan(geo[i].k1) && geo[i].normal_flags == 8);
        } else {
            CHECK(memcmp(out + 3 * i, fout + 3 * j, 3 * sizeof *out) == 0);
            /* field by field: the struct's padding bytes are not written */
            CHECK(memcmp(geo[i].normal, fgeo[j].normal, sizeof geo[i].normal) == 0);
            CHECK(geo[i].k1 == fgeo[j].k1 && geo[i].k2 == fgeo[j].k2);
            CHECK(geo[i].covariance_quotient == fgeo[j].covariance_quotient);
            CHECK(geo[i].normal_flags == fgeo[j].normal_flags);
            j++;
        }
    }
    CHECK_STATUS(nbhd_estimate_normals(&pts, &no, &nout), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_estimate_normals(&fpts, NULL, &fnout), NBHD_STATUS_OK);
    for (i = 0, j = 0; i < n; i++) {
        if (i % 7 == 3) {
            CHECK(isnan(nrm[3 * i]) && flags[i] == 8);
        } else {
            CHECK(memcmp(nrm + 3 * i, fnrm + 3 * j, 3 * sizeof *nrm) == 0 && flags[i] == fflags[j]);
            j++;
        }
    }
    CHECK_STATUS(nbhd_estimate_curvatures(&pts, &o, geo, NULL), NBHD_STATUS_OK);
    for (i = 0; i < n; i++) CHECK((i % 7 == 3) == (geo[i].normal_flags == 8));
    /* In place: the holes stay NaN, the other points move. */
    memcpy(out, p, 3 * n * sizeof *p);
    CHECK_STATUS(nbhd_smooth_robust(&pts, &ro, out, NULL, NULL), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_smooth_robust(&pts, &ro, p, geo, NULL), NBHD_STATUS_OK);
    for (i = 0; i < n; i++) {
        if (i % 7 == 3) CHECK(isnan(p[3 * i]) && geo[i].normal_flags == 8);
        else CHECK(p[3 * i] == out[3 * i] && isfinite(geo[i].normal[0]));
    }
    /* Nothing but holes: nothing to compute. */
    pts.count = 1;
    pts.data = p + 3 * 3;
    CHECK_STATUS(nbhd_smooth(&pts, &o, out, NULL, NULL), NBHD_STATUS_EMPTY_INPUT);
    free(p); free(fin); free(out); free(fout); free(nrm); free(fnrm);
    free(flags); free(fflags); free(geo); free(fgeo);
}

/* epsilon = 0.01 meant as a length but left RELATIVE (0.01 h): refused with DEGENERATE and a
 * message giving epsilon in the points' units; the same 0.01 taken as ABSOLUTE is fine. */
static void test_units_are_not_silent(size_t n) {
    double *p = malloc(3 * n * sizeof *p), *nrm = malloc(3 * n * sizeof *nrm);
    nbhd_normal_options no = nbhd_normal_options_default();
    nbhd_normals_output nout = packed_normals(nrm, NULL);
    nbhd_points pts;
    sphere(p, n, 0.0);
    pts = describe(p, n, 0, NBHD_SCALAR_TYPE_F64);
    no.epsilon = 0.01;
    CHECK_STATUS(nbhd_estimate_normals(&pts, &no, &nout), NBHD_STATUS_DEGENERATE);
    CHECK_MESSAGE("epsilon resolved to");
    CHECK_MESSAGE("in the points' units");
    CHECK_MESSAGE("ABSOLUTE");
    no.epsilon = 6.0 * spacing(n);
    no.epsilon_units = NBHD_UNITS_ABSOLUTE;
    CHECK_STATUS(nbhd_estimate_normals(&pts, &no, &nout), NBHD_STATUS_OK);
    free(p);
    free(nrm);
}

/* Normals and PCL's curvature written in place into a PCL-like record (float normal[4], float
 * curvature, 3 floats of padding: the layout of pcl::Normal), the other bytes untouched;
 * the same values as the packed double output and nbhd_estimate_curvatures' surface
 * variation, rounded to float. */
typedef struct {
    float normal[4];
    float curvature;
    float pad[3];
} pcl_like_normal;

static void test_normals_into_a_pcl_layout(size_t n) {
    double *p = malloc(3 * n * sizeof *p), *nrm = malloc(3 * n * sizeof *nrm);
    pcl_like_normal *rec = malloc(n * sizeof *rec);
    nbhd_point_geometry *geo = malloc(n * sizeof *geo);
    nbhd_normals_output nout = packed_normals(nrm, NULL), rout;
    nbhd_points pts;
    size_t i;
    sphere(p, n, 0.1 * spacing(n));
    pts = describe(p, n, 0, NBHD_SCALAR_TYPE_F64);
    memset(rec, 0x5a, n * sizeof *rec);
    memset(&rout, 0, sizeof rout);
    rout.normals = &rec[0].normal[0];
    rout.normals_stride = sizeof *rec;
    rout.scalar_type = NBHD_SCALAR_TYPE_F32;
    rout.curvature = &rec[0].curvature;
    rout.curvature_stride = sizeof *rec;
    CHECK_STATUS(nbhd_estimate_normals(&pts, NULL, &rout), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_estimate_normals(&pts, NULL, &nout), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_estimate_curvatures(&pts, NULL, geo, NULL), NBHD_STATUS_OK);
    for (i = 0; i < n; i++) {
        const unsigned char *pad = (const unsigned char *)rec[i].pad;
        size_t b;
        CHECK(rec[i].normal[0] == (float)nrm[3 * i] && rec[i].normal[1] == (float)nrm[3 * i + 1] &&
              rec[i].normal[2] == (float)nrm[3 * i + 2]);
        CHECK(rec[i].curvature == (float)geo[i].covariance_quotient);
        CHECK(rec[i].curvature >= 0.0f && rec[i].curvature <= 1.0f / 3.0f + 1e-6f);
        for (b = 0; b < sizeof rec[i].pad; b++) CHECK(pad[b] == 0x5a);
        CHECK(((const unsigned char *)&rec[i].normal[3])[0] == 0x5a);
    }
    free(p);
    free(nrm);
    free(rec);
    free(geo);
}

/* Field by field (the struct has padding bytes, which memcmp would read). */
static bool same_geometry(const nbhd_point_geometry *a, const nbhd_point_geometry *b, size_t n) {
    size_t i;
    for (i = 0; i < n; i++) {
        const nbhd_point_geometry *x = &a[i], *y = &b[i];
        if (memcmp(x->normal, y->normal, sizeof x->normal) != 0 || x->k1 != y->k1 || x->k2 != y->k2 ||
            memcmp(x->dir1, y->dir1, sizeof x->dir1) != 0 || memcmp(x->dir2, y->dir2, sizeof x->dir2) != 0 ||
            x->mean_curvature != y->mean_curvature || x->max_principal_curvature != y->max_principal_curvature ||
            x->covariance_quotient != y->covariance_quotient ||
            x->anisotropic_mean_curvature != y->anisotropic_mean_curvature ||
            x->principal_curvature_quotient != y->principal_curvature_quotient ||
            x->max_covariance != y->max_covariance || x->normal_flags != y->normal_flags ||
            x->feature != y->feature || x->interior != y->interior)
            return false;
    }
    return true;
}

/* Smoothing what the caller already has: the points of a built tree, or points with a
 * neighbourhood table. Every result is the bytes of the point-buffer call on the same
 * neighbourhoods (a k-nearest table with at least the call's k; the tree's own search). */
static void test_from_tree_and_table(size_t n) {
    double *p = malloc(3 * n * sizeof *p);
    double *want = malloc(3 * n * sizeof *want), *got = malloc(3 * n * sizeof *got);
    nbhd_point_geometry *gw = malloc(n * sizeof *gw), *gg = malloc(n * sizeof *gg);
    nbhd_smooth_summary sw, sg;
    nbhd_smooth_options so = nbhd_smooth_options_default();
    nbhd_robust_options ro = nbhd_robust_options_default();
    nbhd_build_options bo = nbhd_build_options_default();
    nbhd_tree *tree = NULL;
    nbhd_neighborhoods *knn48 = NULL, *knn3 = NULL;
    nbhd_neighborhood_spec spec = {NBHD_NEIGHBORHOOD_KIND_KNN, 48, 0.0};
    nbhd_points pts;

    sphere(p, n, 0.5 * spacing(n));
    pts = describe(p, n, 0, NBHD_SCALAR_TYPE_F64);
    CHECK_STATUS(nbhd_tree_build(&pts, &bo, &tree), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_tree_neighborhoods(tree, &spec, NULL, &knn48), NBHD_STATUS_OK);

    /* faithful: tree and table against the points */
    CHECK_STATUS(nbhd_smooth(&pts, &so, want, gw, &sw), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_smooth_tree(tree, &so, got, gg, &sg), NBHD_STATUS_OK);
    CHECK(memcmp(want, got, 3 * n * sizeof *got) == 0);
    CHECK(same_geometry(gw, gg, n) && memcmp(&sw, &sg, sizeof sg) == 0);
    memset(got, 0, 3 * n * sizeof *got);
    CHECK_STATUS(nbhd_smooth_table(&pts, knn48, &so, got, gg, &sg), NBHD_STATUS_OK);
    CHECK(memcmp(want, got, 3 * n * sizeof *got) == 0);
    CHECK(same_geometry(gw, gg, n) && memcmp(&sw, &sg, sizeof sg) == 0);

    /* normals and curvatures */
    CHECK_STATUS(nbhd_estimate_curvatures(&pts, &so, gw, &sw), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_estimate_curvatures_tree(tree, &so, gg, &sg), NBHD_STATUS_OK);
    CHECK(same_geometry(gw, gg, n) && memcmp(&sw, &sg, sizeof sg) == 0);
    memset(gg, 0, n * sizeof *gg);
    CHECK_STATUS(nbhd_estimate_curvatures_table(&pts, knn48, &so, gg, &sg), NBHD_STATUS_OK);
    CHECK(same_geometry(gw, gg, n));

    /* robust: its k_plane = 48 nearest */
    ro.max_iterations = 3;
    CHECK_STATUS(nbhd_smooth_robust(&pts, &ro, want, NULL, &sw), NBHD_STATUS_OK);
    CHECK_STATUS(nbhd_smooth_robust_tree(tree, &ro, got, NULL, &sg), NBHD_STATUS_OK);
    CHECK(memcmp(want, got, 3 * n * sizeof *got) == 0 && memcmp(&sw, &sg, sizeof sg) == 0);
    memset(got, 0, 3 * n * sizeof *got);
    CHECK_STATUS(nbhd_smooth_robust_table(&pts, knn48, &ro, got, NULL, &sg), NBHD_STATUS_OK);
    CHECK(memcmp(want, got, 3 * n * sizeof *got) == 0);

    /* refusals: NULLs, a table of another cloud, a table with each point in its own row */
    CHECK_STATUS(nbhd_smooth_tree(NULL, &so, got, NULL, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("tree");
    CHECK_STATUS(nbhd_smooth_tree(tree, &so, NULL, NULL, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_STATUS(nbhd_smooth_table(&pts, NULL, &so, got, NULL, NULL), NBHD_STATUS_NULL_POINTER);
    CHECK_MESSAGE("table");
    pts.count = n - 1;
    CHECK_STATUS(nbhd_smooth_table(&pts, knn48, &so, got, NULL, NULL), NBHD_STATUS_INVALID_OPTION);
    CHECK_MESSAGE("rows");
    pts.count = n;
    {
        nbhd_table_options to = nbhd_table_options_default();
        nbhd_neighborhood_spec s3 = {NBHD_NEIGHBORHOOD_KIND_KNN, 3, 0.0};
        to.exclude_self = false;
        CHECK_STATUS(nbhd_tree_neighborhoods(tree, &s3, &to, &knn3), NBHD_STATUS_OK);
        CHECK_STATUS(nbhd_estimate_curvatures_table(&pts, knn3, &so, gg, NULL),
                     NBHD_STATUS_INVALID_OPTION);
        CHECK_MESSAGE("itself");
    }
    nbhd_neighborhoods_free(knn3);
    nbhd_neighborhoods_free(knn48);
    nbhd_tree_free(tree);
    free(p);
    free(want);
    free(got);
    free(gw);
    free(gg);
}

int main(int argc, char **argv) {
    size_t n = argc > 1 ? (size_t)strtoul(argv[1], NULL, 10) : 3000;
    test_defaults();
    test_normals_and_curvatures(n);
    test_smooth_in_place(n);
    test_threads_agree(n / 2);
    test_robust(n);
    test_errors();
    test_non_finite_skip(n);
    test_units_are_not_silent(n);
    test_normals_into_a_pcl_layout(n);
    test_from_tree_and_table(n);
    printf("smooth_test: %d checks, %d failed\n", checks, failures);
    return failures == 0 ? 0 : 1;
}
