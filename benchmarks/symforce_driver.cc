// The SymForce alternative of benchmarks/run.py: SymForce-generated C++ routines (sk::Rigid,
// sk::RigidRes, sk::Linear, sk::Newton, sk::RigidPoints, sk::DevExact) driven by the algorithm of
// symkin's generated C evaluator, step for step: closed-form rigid angles, SK_POLISH Newton
// polish steps, first-order delta, Newton on delta with symkin's stopping rule (symkin.core.settings).
// benchmarks/symforce_alt.py writes sk_config.h (sizes, indices, solver settings, the routine
// headers) beside it and compiles both with Eigen; sf_bench_loop is timed inside C++.
#include <time.h>

#include <cmath>
#include <cstddef>

#include "kernels.h"
#include "sk_config.h"

namespace {
const int M = SK_M, K = SK_K, NIN = SK_NIN, NP = SK_NP, NPAR = SK_NPAR, ND = SK_ND;
const int in_idx[NIN > 0 ? NIN : 1] = {SK_INPUT_INDEX};
const int unk_idx[K > 0 ? K : 1] = {SK_UNKNOWN_INDEX};
const double two_pi = 6.283185307179586476925286766559006;
typedef Eigen::Matrix<double, NIN, 1> InVec;
typedef Eigen::Matrix<double, NPAR, 1> ParVec;
typedef Eigen::Matrix<double, M, 1> ThVec;
typedef Eigen::Matrix<double, (K > 0 ? K : 1), 1> DeVec;

/* symkin's Gaussian elimination with partial pivoting, verbatim. */
int solve(int n, double *a, double *b)
{
    int i, j, c, p;
    for (c = 0; c < n; ++c) {
        double best = std::fabs(a[c * n + c]);
        p = c;
        for (i = c + 1; i < n; ++i) {
            if (std::fabs(a[i * n + c]) > best) { best = std::fabs(a[i * n + c]); p = i; }
        }
        if (!(best > 0.0) || !std::isfinite(best)) return 1;
        if (p != c) {
            double t;
            for (j = 0; j < n; ++j) { t = a[c * n + j]; a[c * n + j] = a[p * n + j]; a[p * n + j] = t; }
            t = b[c]; b[c] = b[p]; b[p] = t;
        }
        for (i = c + 1; i < n; ++i) {
            const double f = a[i * n + c] / a[c * n + c];
            for (j = c; j < n; ++j) a[i * n + j] -= f * a[c * n + j];
            b[i] -= f * b[c];
        }
    }
    for (i = n - 1; i >= 0; --i) {
        double s = b[i];
        for (j = i + 1; j < n; ++j) s -= a[i * n + j] * b[j];
        b[i] = s / a[i * n + i];
    }
    return 0;
}

int evaluate(const double *inputs, const double *params, double *out)
{
    InVec x;
    ParVec p;
    ThVec theta = ThVec::Zero();
    DeVec delta = DeVec::Zero();
    int i;
    for (i = 0; i < NIN; ++i) x(i) = inputs[i];
    for (i = 0; i < NPAR; ++i) p(i) = params[i];
    for (i = 0; i < NIN; ++i) theta(in_idx[i]) = inputs[i];
#if SK_HAS_UNKNOWNS
    {
        const auto sol = sk::Rigid<double>(x, p);
        for (i = 0; i < ND; ++i) if (!(sol(K + i) >= 0.0)) return 1;
        for (i = 0; i < K; ++i) theta(unk_idx[i]) = std::remainder(sol(i), two_pi);
        for (int it = 0; it < SK_POLISH; ++it) {      /* the same polish steps as symkin's C */
            const auto rr = sk::RigidRes<double>(theta, p);
            const auto ll = sk::Linear<double>(theta, p);
            double lin[K * K > 0 ? K * K : 1], res[K > 0 ? K : 1];
            for (i = 0; i < K * K; ++i) lin[i] = ll(i);
            for (i = 0; i < K; ++i) res[i] = (i % 3 == 0) ? std::remainder(rr(i), two_pi) : rr(i);
            if (solve(K, lin, res)) return 1;
            for (i = 0; i < K; ++i) theta(unk_idx[i]) -= res[i];
        }
    }
#endif
#if SK_NEEDS_LOOPS
    {
        const auto ll = sk::Linear<double>(theta, p);
        double lin[K * K > 0 ? K * K : 1], d[K > 0 ? K : 1];
        for (i = 0; i < K * K; ++i) lin[i] = ll(i);
        for (i = 0; i < K; ++i) d[i] = -ll(K * K + i);
        if (solve(K, lin, d)) return 1;
        for (i = 0; i < K; ++i) delta(i) = d[i];
        double previous = HUGE_VAL;
        int it, converged = 0;
        for (it = 0; it < SK_ITERATIONS && !converged; ++it) {
            const auto nw = sk::Newton<double>(theta, delta, p);
            double jac[K * K > 0 ? K * K : 1], f[K > 0 ? K : 1];
            double size = 0.0, change = 0.0;
            for (i = 0; i < K; ++i) f[i] = nw(i);
            for (i = 0; i < K * K; ++i) jac[i] = nw(K + i);
            if (solve(K, jac, f)) return 1;
            for (i = 0; i < K; ++i) {
                delta(i) -= f[i];
                if (std::fabs(delta(i)) > size) size = std::fabs(delta(i));
                if (std::fabs(f[i]) > change) change = std::fabs(f[i]);
            }
            converged = change <= SK_STOP * size || size == 0.0
                        || (change >= SK_STALL_RATIO * previous && change <= SK_STALL * size);
            previous = change;
        }
        if (!converged) return 2;
    }
#endif
    {
        const auto rig = sk::RigidPoints<double>(theta, p);
        const auto dev = sk::DevExact<double>(theta, delta, p);
        for (i = 0; i < NP; ++i) {
            out[6 * i + 0] = rig(2 * i); out[6 * i + 1] = rig(2 * i + 1);
            out[6 * i + 2] = rig(2 * i) + dev(2 * i); out[6 * i + 3] = rig(2 * i + 1) + dev(2 * i + 1);
            out[6 * i + 4] = dev(2 * i); out[6 * i + 5] = dev(2 * i + 1);
        }
    }
    return 0;
}
}  // namespace

extern "C" double sf_bench_loop(const double *inputs, int n_points, const double *params,
                                int reps, double *out, int *failures)
{
    struct timespec t0, t1;
    int r, i, fails = 0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (r = 0; r < reps; ++r) {
        for (i = 0; i < n_points; ++i) {
            if (evaluate(inputs + (std::size_t)i * NIN, params, out + (std::size_t)i * 6 * NP) != 0) ++fails;
        }
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    *failures = fails;
    return (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
}
