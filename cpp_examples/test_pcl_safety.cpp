// ctest: nbhd::PclSearch (include/nbhd_pcl.hpp) where the caller changes things between calls,
// against pcl::search::KdTree given the same cloud. scripts/sanitize-test.sh also builds it
// under AddressSanitizer + UndefinedBehaviorSanitizer, where any out-of-bounds read fails it.
//
//   test_pcl_safety [N]          N random points (default 6000)
//
// 1. A cloud grown and moved after setInputCloud (no new setInputCloud), before and after runs
//    of index queries have made nbhd's all-point tables: a point appended to the cloud, a point
//    moved in place and an unchanged point are asked about in every form (by reference to the
//    cloud's point, by a copy, by cloud and index, by input position, in batches). PCL reads
//    the query point when the call is made and searches the points of the last setInputCloud;
//    nbhd must give the same answers. Also with an index subset that lists points twice.
// 2. Several threads on one search object, index and coordinate queries interleaved (the
//    tables made while the others query), with and without a subset listing points twice:
//    every answer equals pcl::search::KdTree's, computed before on one thread.
// Exit 1 on any disagreement.
#include <nbhd_pcl.hpp>

#include "common/search_answers.hpp"

#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <random>
#include <thread>
#include <vector>

using search_answers::compare;
using search_answers::Tally;

using P = pcl::PointXYZ;
using CloudP = pcl::PointCloud<P>;
using SearchP = pcl::search::Search<P>;

/// n points uniform in the unit cube, every 97th an exact copy of an earlier one.
static CloudP::Ptr random_cloud(std::size_t n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    CloudP::Ptr c(new CloudP);
    for (std::size_t i = 0; i < n; ++i) {
        if (i > 0 && i % 97 == 0) c->push_back((*c)[rng() % i]);
        else c->push_back(P(u(rng), u(rng), u(rng)));
    }
    c->width = static_cast<std::uint32_t>(c->size());
    c->height = 1;
    return c;
}

/// One question, asked of either search object.
using Ask = std::function<int(const SearchP&, pcl::Indices&, std::vector<float>&)>;

static void agree(const char* what, const SearchP& kd, const SearchP& nb, const Ask& ask,
                  bool cut, Tally& t) {
    pcl::Indices pi, ni;
    std::vector<float> pd, nd;
    const int a = ask(kd, pi, pd);
    const int b = ask(nb, ni, nd);
    compare(what, pi, pd, ni, nd, a, b, cut, t);
}

constexpr int kK = 8;
constexpr unsigned kMaxNn = 5;

/// Every form of k nearest and radius query around cloud point `i` as the cloud is now.
static void ask_every_form(const CloudP::Ptr& cloud, const SearchP& kd, const SearchP& nb,
                           std::size_t i, double r, bool by_position, Tally& t) {
    const auto c = static_cast<pcl::index_t>(i);
    agree("knn by reference", kd, nb, [&](const SearchP& s, pcl::Indices& x, std::vector<float>& d) {
        return s.nearestKSearch((*cloud)[i], kK, x, d);
    }, true, t);
    agree("knn by copy", kd, nb, [&](const SearchP& s, pcl::Indices& x, std::vector<float>& d) {
        const P copy = (*cloud)[i];
        return s.nearestKSearch(copy, kK, x, d);
    }, true, t);
    agree("knn cloud index", kd, nb, [&](const SearchP& s, pcl::Indices& x, std::vector<float>& d) {
        return s.nearestKSearch(*cloud, c, kK, x, d);
    }, true, t);
    agree("radius by reference", kd, nb, [&](const SearchP& s, pcl::Indices& x, std::vector<float>& d) {
        return s.radiusSearch((*cloud)[i], r, x, d);
    }, false, t);
    agree("radius cloud index", kd, nb, [&](const SearchP& s, pcl::Indices& x, std::vector<float>& d) {
        return s.radiusSearch(*cloud, c, r, x, d);
    }, false, t);
    agree("max_nn by reference", kd, nb, [&](const SearchP& s, pcl::Indices& x, std::vector<float>& d) {
        return s.radiusSearch((*cloud)[i], r, x, d, kMaxNn);
    }, true, t);
    if (!by_position) return;
    agree("knn position", kd, nb, [&](const SearchP& s, pcl::Indices& x, std::vector<float>& d) {
        return s.nearestKSearch(c, kK, x, d);
    }, true, t);
    agree("radius position", kd, nb, [&](const SearchP& s, pcl::Indices& x, std::vector<float>& d) {
        return s.radiusSearch(c, r, x, d);
    }, false, t);
}

/// Runs of same-k / same-radius index queries over every point (what PCL's algorithms ask;
/// nbhd answers them from all-point tables once a run is long), compared as they go: one pass
/// per kind, as a run is a sequence of one kind.
static void index_runs(const CloudP::Ptr& cloud, const SearchP& kd, const SearchP& nb, double r,
                       Tally& t) {
    for (std::size_t i = 0; i < cloud->size(); ++i) {
        const auto c = static_cast<pcl::index_t>(i);
        agree("knn run", kd, nb, [&](const SearchP& s, pcl::Indices& x, std::vector<float>& d) {
            return s.nearestKSearch(*cloud, c, kK, x, d);
        }, true, t);
    }
    for (std::size_t i = 0; i < cloud->size(); ++i) {
        const auto c = static_cast<pcl::index_t>(i);
        agree("radius run", kd, nb, [&](const SearchP& s, pcl::Indices& x, std::vector<float>& d) {
            return s.radiusSearch(*cloud, c, r, x, d);
        }, false, t);
    }
    for (std::size_t i = 0; i < cloud->size(); ++i) {
        const auto c = static_cast<pcl::index_t>(i);
        agree("max_nn run", kd, nb, [&](const SearchP& s, pcl::Indices& x, std::vector<float>& d) {
            return s.radiusSearch(*cloud, c, r, x, d, kMaxNn);
        }, true, t);
    }
}

/// Section 1: the cloud changes after setInputCloud; `warm` runs the index queries that make
/// the tables first. `subset`: setInputCloud with indices listing some points twice.
static void changed_cloud(std::size_t n, bool warm, bool subset) {
    CloudP::Ptr cloud = random_cloud(n, 7);
    const double r = 1.6 / std::cbrt(static_cast<double>(n));  // about 17 points per ball
    pcl::IndicesPtr listed;
    if (subset) {
        listed.reset(new pcl::Indices);
        for (std::size_t i = 0; i < n; i += 2) {
            listed->push_back(static_cast<pcl::index_t>(i));
            if (i % 10 == 0) listed->push_back(static_cast<pcl::index_t>(i));
        }
    }
    pcl::search::KdTree<P> kd;
    nbhd::PclSearch<P> nb;
    kd.setInputCloud(cloud, listed);
    nb.setInputCloud(cloud, listed);
    Tally t;
    if (warm) index_runs(cloud, kd, nb, r, t);
    // Grow the cloud (its storage moves), then move points in place: a tenth of them, among
    // them points the tree holds twice (subset) and copies of other points.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const std::size_t appended = 40;
    for (std::size_t j = 0; j < appended; ++j) {
        if (j % 4 == 0) cloud->push_back((*cloud)[rng() % n]);  // onto an existing point
        else cloud->push_back(P(u(rng), u(rng), u(rng)));
    }
    std::vector<std::size_t> moved;
    for (std::size_t i = 0; i < n; i += 10) {
        (*cloud)[i] = P(u(rng), u(rng), u(rng));
        moved.push_back(i);
    }
    // Appended points: by reference, copy and cloud index (a position is an index of the
    // input, which grew only without a subset).
    for (std::size_t i = n; i < cloud->size(); ++i)
        ask_every_form(cloud, kd, nb, i, r, !subset, t);
    for (std::size_t i : moved) ask_every_form(cloud, kd, nb, i, r, !subset, t);
    for (std::size_t i = 3; i < n; i += 50) ask_every_form(cloud, kd, nb, i, r, !subset, t);
    if (subset) {
        // Positions of the subset, moved points among them.
        for (std::size_t j = 0; j < listed->size(); j += 7) {
            const auto pos = static_cast<pcl::index_t>(j);
            agree("knn subset position", kd, nb,
                  [&](const SearchP& s, pcl::Indices& x, std::vector<float>& d) {
                      return s.nearestKSearch(pos, kK, x, d);
                  }, true, t);
            agree("radius subset position", kd, nb,
                  [&](const SearchP& s, pcl::Indices& x, std::vector<float>& d) {
                      return s.radiusSearch(pos, r, x, d);
                  }, false, t);
        }
    }
    // The runs again, over the grown cloud: the tables' rows of moved points must not be used.
    index_runs(cloud, kd, nb, r, t);
    // Batches over appended, moved and unchanged points.
    pcl::Indices batch;
    for (std::size_t i = 0; i < cloud->size(); i += 9) batch.push_back(static_cast<pcl::index_t>(i));
    std::vector<pcl::Indices> bpi, bni;
    std::vector<std::vector<float>> bpd, bnd;
    kd.nearestKSearch(*cloud, batch, kK, bpi, bpd);
    nb.nearestKSearch(*cloud, batch, kK, bni, bnd);
    for (std::size_t i = 0; i < batch.size(); ++i)
        compare("knn batch", bpi[i], bpd[i], bni[i], bnd[i], static_cast<int>(bpi[i].size()),
                static_cast<int>(bni[i].size()), true, t);
    // Past the end of the cloud (PCL asserts): nothing, and no read outside the cloud.
    pcl::Indices ni;
    std::vector<float> nd;
    const auto past = static_cast<pcl::index_t>(cloud->size());
    EXPECT(nb.nearestKSearch(*cloud, past, kK, ni, nd) == 0 && ni.empty(), "past the end");
    EXPECT(nb.radiusSearch(*cloud, past, r, ni, nd) == 0 && ni.empty(), "past the end");
    EXPECT(nb.nearestKSearch(*cloud, -1, kK, ni, nd) == 0 && ni.empty(), "index -1");
    EXPECT(nb.nearestKSearch(listed ? static_cast<pcl::index_t>(listed->size()) : past, kK, ni,
                             nd) == 0,
           "position past the end");
    std::printf("  changed cloud%s%s: %zu queries, %zu neighbours, %zu tie runs, %zu mismatches\n",
                warm ? ", tables made first" : "", subset ? ", subset with repeats" : "",
                t.queries, t.neighbours, t.tie_runs, t.mismatches);
    EXPECT(t.mismatches == 0, "changed cloud warm=%d subset=%d", warm, subset);
}

/// Section 2: `threads` threads query one object, interleaving the query forms, each point's
/// answer compared with the one pcl::search::KdTree gave on one thread.
static void threads_interleaved(std::size_t n, unsigned threads, bool subset) {
    CloudP::Ptr cloud = random_cloud(n, 3);
    const double r = 1.6 / std::cbrt(static_cast<double>(n));
    pcl::IndicesPtr listed;
    if (subset) {
        listed.reset(new pcl::Indices);
        for (std::size_t i = 0; i < n; ++i) {
            if (i % 3 == 2) continue;
            listed->push_back(static_cast<pcl::index_t>(i));
            if (i % 5 == 0) listed->push_back(static_cast<pcl::index_t>(i));
        }
    }
    pcl::search::KdTree<P> kd;
    kd.setInputCloud(cloud, listed);
    std::vector<pcl::Indices> want_k(n), want_r(n);
    std::vector<std::vector<float>> want_kd(n), want_rd(n);
    for (std::size_t i = 0; i < n; ++i) {
        kd.nearestKSearch((*cloud)[i], kK, want_k[i], want_kd[i]);
        kd.radiusSearch((*cloud)[i], r, want_r[i], want_rd[i]);
    }
    nbhd::PclSearch<P> nb;
    nb.setTableThreads(2);
    nb.setInputCloud(cloud, listed);
    std::vector<Tally> tallies(threads);
    std::vector<std::thread> pool;
    for (unsigned w = 0; w < threads; ++w) {
        pool.emplace_back([&, w] {
            Tally& t = tallies[w];
            pcl::Indices x;
            std::vector<float> d;
            for (int round = 0; round < 2; ++round) {
                for (std::size_t j = w; j < n; j += threads) {
                    const std::size_t i = (j * 7919) % n;  // a spread order, each point once
                    const auto c = static_cast<pcl::index_t>(i);
                    // The index path (by index, by reference to the cloud's point) asks one
                    // kind per round, k nearest then radius, so that its run grows and a table
                    // is made while the other threads query; a copy asks the other kind.
                    const unsigned form = static_cast<unsigned>((j / threads) % 4);
                    const bool asked_knn = (round == 0) != (form == 3);
                    const P copy = (*cloud)[i];
                    int m;
                    if (form == 3)
                        m = asked_knn ? nb.nearestKSearch(copy, kK, x, d) : nb.radiusSearch(copy, r, x, d);
                    else if (form == 1)
                        m = asked_knn ? nb.nearestKSearch((*cloud)[i], kK, x, d)
                                      : nb.radiusSearch((*cloud)[i], r, x, d);
                    else
                        m = asked_knn ? nb.nearestKSearch(*cloud, c, kK, x, d)
                                      : nb.radiusSearch(*cloud, c, r, x, d);
                    if (asked_knn)
                        compare("thread knn", want_k[i], want_kd[i], x, d,
                                static_cast<int>(want_k[i].size()), m, true, t);
                    else
                        compare("thread radius", want_r[i], want_rd[i], x, d,
                                static_cast<int>(want_r[i].size()), m, false, t);
                }
            }
        });
    }
    for (auto& th : pool) th.join();
    Tally all;
    for (const Tally& t : tallies) {
        all.queries += t.queries;
        all.neighbours += t.neighbours;
        all.tie_runs += t.tie_runs;
        all.mismatches += t.mismatches;
    }
    std::printf("  %u threads%s: %zu queries, %zu neighbours, %zu tie runs, %zu mismatches\n",
                threads, subset ? ", subset with repeats" : "", all.queries, all.neighbours,
                all.tie_runs, all.mismatches);
    EXPECT(all.mismatches == 0 && all.queries == 2 * n, "threads subset=%d", subset);
}

int main(int argc, char** argv) {
    const std::size_t n = argc >= 2 ? std::strtoul(argv[1], nullptr, 10) : 6000;
    if (n < 100) {
        std::fprintf(stderr, "usage: %s [N >= 100]\n", argv[0]);
        return 2;
    }
    std::printf("nbhd::PclSearch against pcl::search::KdTree, %zu random points\n", n);
    for (bool subset : {false, true})
        for (bool warm : {false, true}) changed_cloud(n, warm, subset);
    for (bool subset : {false, true}) threads_interleaved(n, 4, subset);
    std::printf("%s\n", search_answers::failures == 0 ? "all agree" : "DISAGREEMENTS");
    return search_answers::failures == 0 ? 0 : 1;
}
