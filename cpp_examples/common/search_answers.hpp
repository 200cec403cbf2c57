// Shared by the ctests of nbhd::PclSearch (test_pcl_backend, test_pcl_safety): a failure
// counter with EXPECT, and the comparison of one answer of pcl::search::KdTree with nbhd's.
#pragma once

#include <pcl/types.h>

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <vector>

namespace search_answers {

inline int failures = 0;

struct Tally {
    std::size_t queries = 0, neighbours = 0, tie_runs = 0, mismatches = 0;
};

/// PCL's answer sorted by (squared distance, index), then compared with nbhd's.
inline void compare(const char* what, pcl::Indices pi, std::vector<float> pd,
                    const pcl::Indices& ni, const std::vector<float>& nd, int pr, int nr,
                    bool cut, Tally& t) {
    ++t.queries;
    std::vector<std::size_t> o(pi.size());
    for (std::size_t i = 0; i < o.size(); ++i) o[i] = i;
    std::sort(o.begin(), o.end(), [&](std::size_t a, std::size_t b) {
        return pd[a] != pd[b] ? pd[a] < pd[b] : pi[a] < pi[b];
    });
    pcl::Indices si;
    std::vector<float> sd;
    for (std::size_t i : o) {
        si.push_back(pi[i]);
        sd.push_back(pd[i]);
    }
    bool ok = pr == nr && si.size() == ni.size() && sd.size() == nd.size() &&
              static_cast<std::size_t>(nr) == ni.size();
    bool tie = false;
    for (std::size_t i = 0; ok && i < si.size(); ++i) {
        if (std::memcmp(&sd[i], &nd[i], sizeof(float)) != 0) ok = false;
        else if (si[i] != ni[i]) {
            // Allowed only in the last run of equal distances of an answer cut at k.
            if (cut && sd[i] == sd.back()) tie = true;
            else ok = false;
        }
    }
    t.neighbours += ni.size();
    if (tie) ++t.tie_runs;
    if (!ok) {
        if (++t.mismatches <= 3) {
            std::fprintf(stderr, "  %s: PCL %d [", what, pr);
            for (std::size_t i = 0; i < si.size() && i < 20; ++i)
                std::fprintf(stderr, " %d:%.9g", si[i], sd[i]);
            std::fprintf(stderr, " ] nbhd %d [", nr);
            for (std::size_t i = 0; i < ni.size() && i < 20; ++i)
                std::fprintf(stderr, " %d:%.9g", ni[i], nd[i]);
            std::fprintf(stderr, " ]\n");
        }
    }
}

}  // namespace search_answers

#define EXPECT(cond, ...)                                                \
    do {                                                                 \
        if (!(cond)) {                                                   \
            ++search_answers::failures;                                  \
            std::fprintf(stderr, "FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond); \
            std::fprintf(stderr, __VA_ARGS__);                           \
            std::fprintf(stderr, "\n");                                  \
        }                                                                \
    } while (0)
