/*
 * symkin's C runtime (docs/runtime.md): what every generated evaluator runs around its
 * mechanism's routines. A generated <name>.c holds the text below the marker line, verbatim
 * (templates/c/source.c.j2), so the pair <name>.h / <name>.c stays self-contained: C99, libm
 * only, no allocation, no data but constants, thread-safe.
 *
 * Before that text the generated file defines its sizes (an enum: SK_M hinges, SK_K unknowns of
 * the loops, SK_NI inputs, SK_NPAR parameters, SK_NP points, SK_NL reported links, SK_NV
 * variables of the sensitivities, SK_NQ constants of the routines, SK_OUT the largest routine
 * output plus one) and its routines; after it, its tables (one sk_mechanism) and its public
 * functions, each a call into this file.
 *
 * The parts a mechanism may not need are sections `#if defined(SK_<FEATURE>) ...` (#else,
 * #endif): SK_LOOPS (it has loops: SK_K > 0), SK_CLOSED_FORM and SK_CONTINUATION (how its rigid
 * pose is reached), SK_LOADED (the loaded levels), SK_LINKS (link rotations), SK_SENSITIVITY.
 * The emitter resolves them for each mechanism as the preprocessor would
 * (symkin.codegen.templating.runtime), so a generated file holds only the code it runs, without
 * the directives.
 *
 * tests/test_runtime_c.py compiles this file on its own, every feature defined, with a C driver
 * that defines those sizes and small routines of its own, and checks every function against
 * independent computations.
 */
#include <math.h>
#include <stddef.h>

/* ---- symkin runtime: every generated .c holds what follows ---- */

/* symkin runtime (templates/c/runtime.c, docs/runtime.md; tested on its own by
   tests/test_runtime_c.py): dense linear algebra, the Newton and continuation drivers, the
   evaluation of a configuration at every level, the sensitivities and the batch loops, all
   driven by the tables of one sk_mechanism (this mechanism's part of it). */

#define SK_TWO_PI 6.283185307179586476925286766559006

/* The routines: one to three input arrays, then the output array. */
typedef void (*sk_fn1)(const double *a, double *out);
typedef void (*sk_fn2)(const double *a, const double *b, double *out);
typedef void (*sk_fn3)(const double *a, const double *b, const double *c, double *out);

#if defined(SK_LOOPS) || defined(SK_LOADED)
/* ---- dense linear algebra ---- */

#if defined(SK_LOOPS)
/* Gaussian elimination with partial pivoting (the first largest pivot) of the n x n row-major
   a, in place, for the n x m row-major right-hand sides b, which become the solution. Returns 0,
   or 1 when a pivot is zero or not finite. */
static int sk_solve_k(double *a, double *b);

static int sk_solve(int n, double *a, int m, double *b)
{
    int i, j, c, p, r;
    if (n == SK_K && m == 1) {
        return sk_solve_k(a, b);
    }
    for (c = 0; c < n; ++c) {
        double best = fabs(a[c * n + c]);
        p = c;
        for (i = c + 1; i < n; ++i) {
            if (fabs(a[i * n + c]) > best) {
                best = fabs(a[i * n + c]);
                p = i;
            }
        }
        if (!(best > 0.0) || !isfinite(best)) {
            return 1;
        }
        if (p != c) {
            double t;
            for (j = c; j < n; ++j) {
                t = a[c * n + j];
                a[c * n + j] = a[p * n + j];
                a[p * n + j] = t;
            }
            for (r = 0; r < m; ++r) {
                t = b[c * m + r];
                b[c * m + r] = b[p * m + r];
                b[p * m + r] = t;
            }
        }
        for (i = c + 1; i < n; ++i) {
            const double f = a[i * n + c] / a[c * n + c];
            for (j = c + 1; j < n; ++j) {
                a[i * n + j] -= f * a[c * n + j];
            }
            for (r = 0; r < m; ++r) {
                b[i * m + r] -= f * b[c * m + r];
            }
        }
    }
    for (r = 0; r < m; ++r) {
        for (i = n - 1; i >= 0; --i) {
            double s = b[i * m + r];
            for (j = i + 1; j < n; ++j) {
                s -= a[i * n + j] * b[j * m + r];
            }
            b[i * m + r] = s / a[i * n + i];
        }
    }
    return 0;
}

/* sk_solve for the loops' SK_K unknowns and one right-hand side (every Newton step of the rigid
   and exact closures, the first-order delta): the same operations in the same order, the same
   bits, with the sizes constants (a third fewer instructions, docs/benchmarks.md). */
static int sk_solve_k(double *a, double *b)
{
    int i, j, c, p;
    for (c = 0; c < SK_K; ++c) {
        double best = fabs(a[c * SK_K + c]);
        p = c;
        for (i = c + 1; i < SK_K; ++i) {
            if (fabs(a[i * SK_K + c]) > best) {
                best = fabs(a[i * SK_K + c]);
                p = i;
            }
        }
        if (!(best > 0.0) || !isfinite(best)) {
            return 1;
        }
        if (p != c) {
            double t;
            for (j = c; j < SK_K; ++j) {
                t = a[c * SK_K + j];
                a[c * SK_K + j] = a[p * SK_K + j];
                a[p * SK_K + j] = t;
            }
            t = b[c];
            b[c] = b[p];
            b[p] = t;
        }
        for (i = c + 1; i < SK_K; ++i) {
            const double f = a[i * SK_K + c] / a[c * SK_K + c];
            for (j = c + 1; j < SK_K; ++j) {
                a[i * SK_K + j] -= f * a[c * SK_K + j];
            }
            b[i] -= f * b[c];
        }
    }
    for (i = SK_K - 1; i >= 0; --i) {
        double s = b[i];
        for (j = i + 1; j < SK_K; ++j) {
            s -= a[i * SK_K + j] * b[j];
        }
        b[i] = s / a[i * SK_K + i];
    }
    return 0;
}
#endif

#if defined(SK_LOADED)

/* sk_solve's elimination kept for later right-hand sides: the multipliers below the diagonal of
   a, U on and above it, the row swaps in piv. Returns 0, or 1 as sk_solve. */
static int sk_lu(int n, double *a, int *piv)
{
    int i, j, c, p;
    for (c = 0; c < n; ++c) {
        double best = fabs(a[c * n + c]);
        p = c;
        for (i = c + 1; i < n; ++i) {
            if (fabs(a[i * n + c]) > best) {
                best = fabs(a[i * n + c]);
                p = i;
            }
        }
        if (!(best > 0.0) || !isfinite(best)) {
            return 1;
        }
        piv[c] = p;
        /* the multipliers of earlier columns stay: sk_lu_solve replays each swap in turn */
        for (j = c; p != c && j < n; ++j) {
            const double t = a[c * n + j];
            a[c * n + j] = a[p * n + j];
            a[p * n + j] = t;
        }
        for (i = c + 1; i < n; ++i) {
            const double f = a[i * n + c] / a[c * n + c];
            a[i * n + c] = f;
            for (j = c + 1; j < n; ++j) {
                a[i * n + j] -= f * a[c * n + j];
            }
        }
    }
    return 0;
}

/* b -> x of a x = b with sk_lu's factors of a: sk_solve's operations for one right-hand side. */
static void sk_lu_solve(int n, const double *a, const int *piv, double *b)
{
    int i, j, c;
    for (c = 0; c < n; ++c) {
        if (piv[c] != c) {
            const double t = b[c];
            b[c] = b[piv[c]];
            b[piv[c]] = t;
        }
        for (i = c + 1; i < n; ++i) {
            b[i] -= a[i * n + c] * b[c];
        }
    }
    for (i = n - 1; i >= 0; --i) {
        double s = b[i];
        for (j = i + 1; j < n; ++j) {
            s -= a[i * n + j] * b[j];
        }
        b[i] = s / a[i * n + i];
    }
}
#endif
#endif
#if defined(SK_CLOSED_FORM) || defined(SK_LINKS)

/* remainder(x, 2 pi): x itself when |x| <= pi (exactly what remainder returns), without the
   call. */
static double sk_wrap(double x)
{
    return fabs(x) <= 0.5 * SK_TWO_PI ? x : remainder(x, SK_TWO_PI);
}
#endif

/* n entries of x set to NaN (no partial result after a failure); x may be NULL. */
static void sk_nan(double *x, int n)
{
    int i;
    for (i = 0; x != NULL && i < n; ++i) {
        x[i] = NAN;
    }
}

/* ---- Newton and continuation ---- */

/* When a Newton iteration stops (symkin.core.settings): after `iterations` steps at most, and
   once a step (its largest entry) is at most `tolerance`, or at most `converged` times the
   largest unknown (with converged > 0: quadratic convergence leaves the unknowns exact; a
   step onto all-zero unknowns goes on: at a tiny input the polish passes through zero), or
   has stalled at rounding: at least `stall_ratio` times the
   previous step and at most `stalled` times the largest unknown. */
typedef struct {
    int iterations;
    double tolerance;
    double converged;
    double stalled;
    double stall_ratio;
    double residual;    /* > 0: also stop once every residual is this small relative to the size
                           of its terms (a closure's S, symkin.core.settings 3b) */
} sk_rule;

#if defined(SK_LOOPS)

/* Whether Newton stops after a step `change` (largest entry), the unknowns now at most `size`
   in magnitude, the previous step `previous` (HUGE_VAL before the second): the one stopping
   test of every Newton iteration. */
static int sk_newton_stop(const sk_rule *rule, double change, double size,
                          double previous, int noise)
{
    return change <= rule->tolerance || noise
           || (rule->converged > 0.0 && change <= rule->converged * size)
           || (change >= rule->stall_ratio * previous && change <= rule->stalled * size);
}

/* Whether every residual f[r] of a system (f, then its row-major Jacobian J, n x n) at x is at
   the rounding level of its terms: |f_r| <= residual (scale_r + sum_j |J_rj x_j|). */
static int sk_residual_noise(int n, const double *fj, const double *x, const double *scale,
                             double residual)
{
    int r, j;
    for (r = 0; r < n; ++r) {
        double terms = fabs(scale[r]);
        for (j = 0; j < n; ++j) {
            terms += fabs(fj[n + r * n + j] * x[j]);
        }
        if (!(fabs(fj[r]) <= residual * terms)) {
            return 0;
        }
    }
    return 1;
}

/* A system of n equations: at the unknowns x, its residual f (n), then its Jacobian (n x n,
   row-major), into fj. */
typedef void (*sk_system_fn)(const void *ctx, const double *x, double *fj);

/* Newton on `system` from x: each step solves J s = f and subtracts s from the unknowns
   (x[index[i]], or x[i] when index is NULL) until `rule` stops it. fj (n + n * n doubles) is
   workspace; with `evaluated` it holds the system at x already. Returns 0 (stopped), 1 (a
   Jacobian singular or not finite) or 2 (not stopped within rule->iterations steps). With
   rule->residual > 0, `scale` (n: the size of each residual's constant terms; index NULL)
   lets a residual at rounding stop it too (sk_residual_noise). */
static int sk_newton_solve(sk_system_fn system, const void *ctx, int n, const int *index,
                           const sk_rule *rule, const double *scale, double *x, double *fj,
                           int evaluated)
{
    double previous = HUGE_VAL;
    int it, i;
    for (it = 0; it < rule->iterations; ++it) {
        double change = 0.0, size = 0.0;
        int noise;
        if (it > 0 || !evaluated) {
            system(ctx, x, fj);
        }
        noise = rule->residual > 0.0 && sk_residual_noise(n, fj, x, scale, rule->residual);
        if (sk_solve(n, fj + n, 1, fj)) {
            return 1;
        }
        for (i = 0; i < n; ++i) {
            double *u = index == NULL ? x + i : x + index[i];
            *u -= fj[i];
            if (fabs(*u) > size) {
                size = fabs(*u);
            }
            if (fabs(fj[i]) > change) {
                change = fabs(fj[i]);
            }
        }
        if (sk_newton_stop(rule, change, size, previous, noise)) {
            return 0;
        }
        previous = change;
    }
    return 2;
}

#endif
#if defined(SK_CONTINUATION)

/* Continuation: stage(ctx, t) at t = 1/steps, 2/steps, ..., 1, each followed by Newton on
   `system` from the previous stage's unknowns (as sk_newton_solve). Returns 0, or the status of the
   first Newton that fails. */
static int sk_continuation(void (*stage)(void *ctx, double t), sk_system_fn system, void *ctx,
                           int steps, int n, const int *index, const sk_rule *rule,
                           double *x, double *fj)
{
    int s, status;
    for (s = 1; s <= steps; ++s) {
        stage(ctx, (double)s / steps);
        status = sk_newton_solve(system, ctx, n, index, rule, NULL, x, fj, 0);
        if (status) {
            return status;
        }
    }
    return 0;
}

/* The number of continuation steps that keeps each at most `step`: ceil(top / step), >= 1. */
static int sk_steps(double top, double step)
{
    const int steps = (int)ceil(top / step);
    return steps < 1 ? 1 : steps;
}
#endif

/* ---- one mechanism's evaluator ---- */

/* Where the blocks of a level's sensitivity routine start (symkin.codegen.plan): with `stage`
   (the level solves a closure E for delta) M, dE/dtheta_u, dE/dv, then dD/dtheta_u, (dD/ddelta,)
   dD/dv of the points' deviations D. */
typedef struct {
    sk_fn3 fn;
    int stage;
    int M, dE_dtheta, dE_dv, dD_dtheta, dD_ddelta, dD_dv;
} sk_sens;

/* A generated level. */
typedef struct {
    int code;           /* the `level` argument that selects it */
    sk_fn3 dev;         /* the points' deviation (theta, delta, q) */
    sk_fn2 linear;      /* the closure it solves for delta: A and r (theta, q); NULL: none */
    sk_fn3 closure;     /* its F and dF/ddelta (theta, delta, q); NULL: A delta = -r only */
    int loaded;         /* 1: m->loaded_solve solves it (q: the parameters, then its deviation) */
    sk_sens sens;       /* its sensitivities (fn NULL: none) */
    sk_fn3 consistency; /* redundant loops: its closure's dropped rows, then their terms' size
                           (theta, delta, q); NULL: none */
    sk_fn2 prepare;     /* the closure's terms without delta (theta, q), once per solve: what
                           `closure` reads in place of theta; NULL: it reads theta */
} sk_level;

/* One mechanism: its tables, routines and solver settings. Routines a mechanism lacks are
   NULL; the layouts of A, r / F, dF / angles, reaches / rotations, deviations are the plan's
   (symkin.codegen.plan), the composite ones' offsets are here. */
typedef struct {
    const double *defaults;         /* the parameters' default values */
    const int *input_index;         /* theta index of every input */
    const int *unknown_index;       /* theta index of every entry of delta */
    int n_fixed;                    /* inputs held at constant angles (derive --fix) */
    const int *fixed_index;
    const double *fixed_angle;
    int n_limits;                   /* hinges whose model holds for |theta| < limit only */
    const int *limit_index;         /* their theta index */
    const int *limit_unknown;       /* their index in delta, or -1 */
    const double *limit;
    int needs_loops;                /* the points need delta */
    int loops_for_links;            /* the links' rotations alone need it */
    sk_fn2 rigid;                   /* closed-form rigid angles and reaches (inputs, params) */
    int n_dyads;
    sk_fn2 rigid_res;               /* rigid closure (theta, params): per loop angle, x, y;
                                       then its Jacobian A (k x k) */
    int n_angular;                  /* the rows of rigid_res that are loops' angle sums */
    const int *angular;
    sk_fn2 linear;                  /* its Jacobian A, r and S (theta, params) */
    int n_rest;                     /* closed-form angles exactly zero with their inputs: */
    const int *rest;                /* (theta index, count, the inputs' positions) ... */
    int n_dropped;                  /* redundant loops: the closure rows left out of the solves */
    sk_fn2 consistency_rigid;       /* their rigid residuals and terms' size (theta, params) */
    double consistent;              /* each must vanish to this fraction of its size */
    sk_fn2 rigid_points;            /* (theta, params) */
    sk_fn2 links;                   /* rotations and their deviations (theta, delta) */
    /* the loaded level (templates/c/reduced.c): (mechanism, inputs, params, theta) -> delta and
       q (the parameters, then the points' deviation); a status */
    int (*loaded_solve)(const void *m, const double *inputs, const double *params,
                        const double *theta, double *delta, double *q);
    const void *loaded;             /* its tables (sk_loaded) */
    /* its sensitivities (templates/c/reduced_sens.c): (mechanism, theta, q, dtheta_u/dv) -> the
       deviation's by every variable; NULL: none */
    int (*loaded_rates)(const void *m, const double *theta, const double *q, const double *thu,
                        double *dev);
    const void *loaded_sens;        /* its tables (sk_loaded_sens) */
    sk_rule rigid_rule;             /* Newton at each continuation step */
    sk_rule polish_rule;            /* after the rigid start */
    sk_rule exact_rule;             /* on every compliant closure */
    double continuation_step;       /* the largest input change of a continuation step */
    double winding;                 /* a loop angle sum this large: a hinge wrapped */
    int n_levels;
    const sk_level *levels;
    sk_fn2 sens_rigid;              /* (theta, params): A, dG/dv, dR/dtheta_u, dR/dv */
    int sr_A, sr_dG_dv, sr_dR_dtheta, sr_dR_dv;
    sk_fn1 sens_chain;              /* d(default of p_j)/dp_k (params); NULL: none */
} sk_mechanism;

/* The level with C code `code`, or NULL. */
static const sk_level *sk_find_level(const sk_mechanism *m, int code)
{
    int i;
    for (i = 0; i < m->n_levels; ++i) {
        if (m->levels[i].code == code) {
            return m->levels + i;
        }
    }
    return NULL;
}

#if defined(SK_LOOPS)

/* Redundant loops (symkin.core.settings, 4): 0 when each dropped closure row con[i] vanishes
   to m->consistent of the size of its terms con[n_dropped + i], else 1 (the loops contradict
   each other). */
static int sk_consistent(const sk_mechanism *m, const double *con)
{
    int i;
    for (i = 0; i < m->n_dropped; ++i) {
        if (!(fabs(con[i]) <= m->consistent * con[m->n_dropped + i])) {
            return 1;
        }
    }
    return 0;
}

/* What the rigid closure's Newton reads: theta is its unknowns' array. */
typedef struct {
    const sk_mechanism *m;
    const double *inputs, *params;
    double *theta;
} sk_rigid_ctx;

/* The rigid closure and its Jacobian A at theta: rigid_res computes both (A alone, not all of
   `linear`: a polish step or a continuation step needs no r nor S). */
static void sk_rigid_system(const void *ctx, const double *theta, double *fj)
{
    const sk_rigid_ctx *c = (const sk_rigid_ctx *)ctx;
    c->m->rigid_res(theta, c->params, fj);
}
#if defined(SK_CONTINUATION)

/* A continuation stage: the inputs (and fixed inputs) at t times their value. */
static void sk_rigid_stage(void *ctx, double t)
{
    sk_rigid_ctx *c = (sk_rigid_ctx *)ctx;
    int i;
    for (i = 0; i < SK_NI; ++i) {
        c->theta[c->m->input_index[i]] = c->inputs[i] * t;
    }
    for (i = 0; i < c->m->n_fixed; ++i) {
        c->theta[c->m->fixed_index[i]] = c->m->fixed_angle[i] * t;
    }
}
#endif

/* The rigid angles of the unknown hinges, theta's inputs set: the closed-form dyads, or
   continuation from the as-fabricated pose; then the winding rule (every loop's angles sum to
   0, not +-2 pi) and the polish (the relative accuracy of small angles). Returns a status. */
static int sk_rigid_pose(const sk_mechanism *m, const double *inputs, const double *params,
                         double *theta)
{
    double fj[SK_K + SK_K * SK_K + 1];
    sk_rigid_ctx c;
    int i;
    c.m = m;
    c.inputs = inputs;
    c.params = params;
    c.theta = theta;
#if defined(SK_CLOSED_FORM)
    if (m->rigid != NULL) {
        double sol[SK_OUT];
        m->rigid(inputs, params, sol);
        for (i = 0; i < m->n_dyads; ++i) {
            if (!(sol[SK_K + i] >= 0.0)) {
                return 1;           /* a loop cannot close: beyond a toggle position */
            }
        }
        for (i = 0; i < SK_K; ++i) {
            theta[m->unknown_index[i]] = sk_wrap(sol[i]);
        }
        /* an angle whose inputs are all zero is exactly zero (its formula rounds to noise) */
        for (i = 0; i < m->n_rest; i += 2 + m->rest[i + 1]) {
            int j, moved = 0;
            for (j = 0; j < m->rest[i + 1]; ++j) {
                moved = moved || inputs[m->rest[i + 2 + j]] != 0.0;
            }
            if (!moved) {
                theta[m->rest[i]] = 0.0;
            }
        }
    }
#endif
#if defined(SK_CONTINUATION)
    if (m->rigid == NULL) {
        double top = 0.0;
        int status;
        for (i = 0; i < SK_NI; ++i) {
            if (fabs(inputs[i]) > top) {
                top = fabs(inputs[i]);
            }
        }
        for (i = 0; i < m->n_fixed; ++i) {
            if (fabs(m->fixed_angle[i]) > top) {
                top = fabs(m->fixed_angle[i]);
            }
        }
        status = sk_continuation(sk_rigid_stage, sk_rigid_system, &c,
                                 sk_steps(top, m->continuation_step), SK_K, m->unknown_index,
                                 &m->rigid_rule, theta, fj);
        if (status) {
            return status;
        }
    }
#endif
    sk_rigid_system(&c, theta, fj);
    for (i = 0; i < m->n_angular; ++i) {
        if (!(fabs(fj[m->angular[i]]) < m->winding)) {
            return 1;
        }
    }
    if (sk_newton_solve(sk_rigid_system, &c, SK_K, m->unknown_index, &m->polish_rule, NULL,
                        theta, fj, 1) == 1) {
        return 1;
    }
    if (m->consistency_rigid != NULL) {
        double con[SK_OUT];
        m->consistency_rigid(theta, params, con);
        return sk_consistent(m, con);
    }
    return 0;
}

/* What a compliant closure's Newton reads. */
typedef struct {
    sk_fn3 closure;
    const double *theta, *q;
} sk_closure_ctx;

static void sk_closure_system(const void *ctx, const double *delta, double *fj)
{
    const sk_closure_ctx *c = (const sk_closure_ctx *)ctx;
    c->closure(c->theta, delta, c->q, fj);
}

/* delta of a closure: A delta = -r (its first-order delta), then with `closure` (F,
   dF/ddelta) Newton from there; with `prepare` the closure reads its terms without delta,
   computed once here, in place of theta. Returns a status. */
static int sk_solve_closure(const sk_mechanism *m, sk_fn2 linear, sk_fn3 closure,
                            sk_fn2 prepare, const double *theta, const double *q, double *delta)
{
    double lin[SK_K * SK_K + 2 * SK_K + 1], fj[SK_K + SK_K * SK_K + 1], scale[SK_K + 1];
    double pre[SK_OUT];
    sk_closure_ctx c;
    int i;
    linear(theta, q, lin);
    for (i = 0; i < SK_K; ++i) {
        delta[i] = -lin[SK_K * SK_K + i];
        scale[i] = lin[SK_K * SK_K + SK_K + i];
    }
    if (sk_solve(SK_K, lin, 1, delta)) {
        return 1;
    }
    if (closure == NULL) {
        return 0;
    }
    c.closure = closure;
    c.theta = theta;
    c.q = q;
    if (prepare != NULL) {
        prepare(theta, q, pre);
        c.theta = pre;
    }
    return sk_newton_solve(sk_closure_system, &c, SK_K, NULL, &m->exact_rule, scale, delta, fj,
                           0);
}
#endif
/* The configuration at level lv: the arguments checked, the rigid angles theta (every hinge)
   and, where the level solves the loops, delta (the non-input hinges; solved for the links'
   rotations only when want_links). *q is what the level's routines read: params, or (loaded) the
   parameters and the deviation solved, written into `constants`. Returns a status code. */
static int sk_pose(const sk_mechanism *m, const sk_level *lv, const double *inputs,
                   const double *params, int want_links, double *theta, double *delta,
                   double *constants, const double **q)
{
    int i;
    *q = params;
    for (i = 0; i < SK_NI; ++i) {
        /* an input is a plate's rotation from the as-fabricated pose: |angle| <= pi */
        if (!isfinite(inputs[i]) || !(fabs(inputs[i]) <= 3.141592653589793)) {
            return 3;
        }
    }
    for (i = 0; i < SK_NPAR; ++i) {
        if (!isfinite(params[i])) {
            return 3;
        }
    }
    for (i = 0; i < SK_M; ++i) {
        theta[i] = 0.0;
    }
    for (i = 0; i < SK_K + 1; ++i) {
        delta[i] = 0.0;
    }
    for (i = 0; i < SK_NI; ++i) {
        theta[m->input_index[i]] = inputs[i];
    }
    for (i = 0; i < m->n_fixed; ++i) {
        theta[m->fixed_index[i]] = m->fixed_angle[i];
    }
#if defined(SK_LOOPS)
    {
        const int status = sk_rigid_pose(m, inputs, params, theta);
        if (status) {
            return status;
        }
    }
#endif
#if defined(SK_LOADED)
    if (lv->loaded) {
        /* the reduced equilibrium (templates/c/reduced.c) gives delta and the deviation */
        const int status = m->loaded_solve(m, inputs, params, theta, delta, constants);
        if (status) {
            return status;
        }
        *q = constants;
    }
#endif
#if defined(SK_LOOPS)
    if (lv->linear != NULL && (m->needs_loops || (m->loops_for_links && want_links))) {
        const int status = sk_solve_closure(m, lv->linear, lv->closure, lv->prepare, theta, *q,
                                              delta);
        if (status) {
            return status;
        }
        if (lv->consistency != NULL) {
            double con[SK_OUT];
            lv->consistency(theta, delta, *q, con);
            if (sk_consistent(m, con)) {
                return 1;
            }
        }
    }
#endif
    for (i = 0; i < m->n_limits; ++i) {
        const int h = m->limit_index[i], u = m->limit_unknown[i];
        /* the hinge's plate holds for |theta| < limit only, rigid and compliant */
        if (!(fabs(theta[h]) <= m->limit[i])
            || (u >= 0 && !(fabs(theta[h] + delta[u]) <= m->limit[i]))) {
            return 1;
        }
    }
    (void)lv;
    (void)want_links;
    (void)constants;
    return 0;
}

/* The points of a solved configuration: per point rigid x, y, compliant x, y, deviation x, y
   into out; when angles is not NULL the rigid then the compliant hinge angles; when links is not
   NULL every reported link's rigid rotation, compliant rotation and deviation. */
static int sk_outputs(const sk_mechanism *m, const sk_level *lv, const double *theta,
                      const double *delta, const double *params, const double *q, double *out,
                      double *angles, double *links)
{
    double rigid[2 * SK_NP + 1], dev[2 * SK_NP + 1];
    int i;
    m->rigid_points(theta, params, rigid);
    lv->dev(theta, delta, q, dev);
    for (i = 0; i < 2 * SK_NP; ++i) {
        if (!isfinite(rigid[i]) || !isfinite(dev[i])) {
            return 2;               /* a non-finite result is never a success */
        }
    }
    for (i = 0; i < SK_NP; ++i) {
        out[6 * i + 0] = rigid[2 * i];
        out[6 * i + 1] = rigid[2 * i + 1];
        out[6 * i + 2] = rigid[2 * i] + dev[2 * i];
        out[6 * i + 3] = rigid[2 * i + 1] + dev[2 * i + 1];
        out[6 * i + 4] = dev[2 * i];
        out[6 * i + 5] = dev[2 * i + 1];
    }
    if (angles != NULL) {
        for (i = 0; i < SK_M; ++i) {
            angles[i] = theta[i];
            angles[SK_M + i] = theta[i];
        }
        for (i = 0; i < SK_K; ++i) {
            angles[SK_M + m->unknown_index[i]] += delta[i];
        }
    }
#if defined(SK_LINKS)
    if (links != NULL) {
        double rot[2 * SK_NL + 1];
        m->links(theta, delta, rot);
        for (i = 0; i < 2 * SK_NL; ++i) {
            if (!isfinite(rot[i])) {
                return 2;
            }
        }
        for (i = 0; i < SK_NL; ++i) {
            links[3 * i + 0] = sk_wrap(rot[i]);
            links[3 * i + 1] = links[3 * i + 0] + rot[SK_NL + i];
            links[3 * i + 2] = rot[SK_NL + i];
        }
    }
#endif
    (void)links;
    return 0;
}

/* <name>_evaluate_pose (the generated header documents the public functions). */
static int sk_evaluate_pose(const sk_mechanism *m, const double *inputs, const double *params,
                            int level, double *out, double *angles, double *links)
{
    double theta[SK_M], delta[SK_K + 1], constants[SK_NQ];
    const double *q;
    const sk_level *lv = sk_find_level(m, level);
    int status;
    if (params == NULL) {
        params = m->defaults;
    }
    status = out == NULL || inputs == NULL || lv == NULL
                 ? 3
                 : sk_pose(m, lv, inputs, params, links != NULL, theta, delta, constants, &q);
    if (status == 0) {
        status = sk_outputs(m, lv, theta, delta, params, q, out, angles, links);
    }
    if (status != 0) {
        sk_nan(out, 6 * SK_NP);
        sk_nan(angles, 2 * SK_M);
        sk_nan(links, 3 * SK_NL);
    }
    return status;
}

/* <name>_evaluate_angles_batch: n rows; the number of rows that failed. */
static int sk_evaluate_rows(const sk_mechanism *m, int n, const double *inputs,
                            const double *params, int level, double *out, double *angles,
                            int *status)
{
    int j, s, failed = 0;
    for (j = 0; j < n; ++j) {
        s = inputs == NULL ? 3 : sk_evaluate_pose(
            m, inputs + (size_t)j * SK_NI, params, level,
            out == NULL ? NULL : out + (size_t)j * 6 * SK_NP,
            angles == NULL ? NULL : angles + (size_t)j * 2 * SK_M, NULL);
        failed += s != 0;
        if (status != NULL) {
            status[j] = s;
        }
    }
    return failed;
}

/* <name>_evaluate_grid: every parameter set at every input row; the number that failed. */
static int sk_evaluate_grid(const sk_mechanism *m, int n_sets, const double *params, int n,
                            const double *inputs, int level, double *out, int *status)
{
    int s, failed = 0;
    for (s = 0; s < n_sets; ++s) {
        failed += sk_evaluate_rows(
            m, n, inputs, params == NULL ? NULL : params + (size_t)s * SK_NPAR, level,
            out == NULL ? NULL : out + (size_t)s * n * 6 * SK_NP, NULL,
            status == NULL ? NULL : status + (size_t)s * n);
    }
    return failed;
}
#if defined(SK_SENSITIVITY)

/* ---- sensitivities (docs/sensitivity.md) ---- */

#if defined(SK_LOOPS)
/* c (m x n) += a (m x p) b (p x n), row-major. */
static void sk_gemm(int m, int p, int n, const double *a, const double *b, double *c)
{
    int i, j, k;
    for (i = 0; i < m; ++i) {
        for (k = 0; k < p; ++k) {
            const double f = a[i * p + k];
            for (j = 0; j < n; ++j) {
                c[i * n + j] += f * b[k * n + j];
            }
        }
    }
}
#endif

/* The parameters' columns of dev and rig (2 SK_NP x SK_NV) made totals: a parameter's default
   that reads earlier ones follows them, last first. Returns 0. */
static int sk_sensitivity_chain(const sk_mechanism *m, const double *params, double *dev,
                                double *rig)
{
    if (m->sens_chain != NULL) {
        double c[SK_NPAR * SK_NPAR + 1];
        int i, j, r;
        m->sens_chain(params, c);
        for (i = SK_NPAR - 1; i >= 0; --i) {
            for (j = i + 1; j < SK_NPAR; ++j) {
                for (r = 0; r < 2 * SK_NP; ++r) {
                    dev[r * SK_NV + i] += c[j * SK_NPAR + i] * dev[r * SK_NV + j];
                    rig[r * SK_NV + i] += c[j * SK_NPAR + i] * rig[r * SK_NV + j];
                }
            }
        }
    }
    return 0;
}

/* The rigid positions' total derivatives (rig, 2 SK_NP x SK_NV) at theta, before the
   parameters' chain, and with loops Theta = d theta_u / dv = -A^-1 dG/dv (th, SK_K x SK_NV).
   Returns 0, or 1 where A is singular. */
static int sk_rigid_rates(const sk_mechanism *m, const double *theta, const double *params,
                          double *th, double *rig)
{
    double sr[SK_OUT];
    int i;
    (void)th;
    m->sens_rigid(theta, params, sr);
#if defined(SK_LOOPS)
    for (i = 0; i < SK_K * SK_NV; ++i) {
        th[i] = -sr[m->sr_dG_dv + i];
    }
    if (sk_solve(SK_K, sr + m->sr_A, SK_NV, th)) {
        return 1;
    }
#endif
    for (i = 0; i < 2 * SK_NP * SK_NV; ++i) {
        rig[i] = sr[m->sr_dR_dv + i];
    }
#if defined(SK_LOOPS)
    sk_gemm(2 * SK_NP, SK_K, SK_NV, sr + m->sr_dR_dtheta, th, rig);
#endif
    return 0;
}

/* The total derivatives of the points' deviations (dev) and rigid positions (rig) by every
   variable, 2 SK_NP x SK_NV row-major (row 2 p + c: component c of point p; columns: the
   parameters, then the inputs), by the implicit-function theorem on the closures: with
   Theta = d theta_u / dv = -A^-1 dG/dv and, where the level solves a closure E for delta,
   Y = -M^-1 (dE/dv + dE/dtheta_u Theta): dD/dv + dD/dtheta_u Theta + dD/ddelta Y. */
static int sk_sensitivity(const sk_mechanism *m, const sk_level *lv, const double *theta,
                          const double *delta, const double *params, const double *q,
                          double *dev, double *rig)
{
    double s[SK_OUT];
    const sk_sens *b = &lv->sens;
    const double *thu = NULL;
    int i;
    double th[SK_K * SK_NV + 1];
#if defined(SK_LOOPS)
    double y[SK_K * SK_NV + 1];
#endif
    (void)q;
    (void)thu;
    if (b->fn == NULL && !(lv->loaded && m->loaded_rates != NULL)) {
        return 3;                   /* a level without closed-form sensitivities */
    }
    if (sk_rigid_rates(m, theta, params, th, rig)) {
        return 1;
    }
#if defined(SK_LOOPS)
    thu = th;
#endif
    if (b->fn == NULL) {
        /* the loaded level: the reduced equilibrium's own (templates/c/reduced_sens.c) */
        if (m->loaded_rates(m, theta, q, thu, dev)) {
            return 1;
        }
        return sk_sensitivity_chain(m, params, dev, rig);
    }
    b->fn(theta, delta, params, s);
#if defined(SK_LOOPS)
    if (b->stage) {
        for (i = 0; i < SK_K * SK_NV; ++i) {
            y[i] = s[b->dE_dv + i];
        }
        sk_gemm(SK_K, SK_K, SK_NV, s + b->dE_dtheta, th, y);
        for (i = 0; i < SK_K * SK_NV; ++i) {
            y[i] = -y[i];
        }
        if (sk_solve(SK_K, s + b->M, SK_NV, y)) {
            return 1;
        }
    }
#endif
    for (i = 0; i < 2 * SK_NP * SK_NV; ++i) {
        dev[i] = s[b->dD_dv + i];
    }
#if defined(SK_LOOPS)
    sk_gemm(2 * SK_NP, SK_K, SK_NV, s + b->dD_dtheta, th, dev);
    if (b->stage) {
        sk_gemm(2 * SK_NP, SK_K, SK_NV, s + b->dD_ddelta, y, dev);
    }
#endif
    return sk_sensitivity_chain(m, params, dev, rig);
}

/* <name>_sensitivity_full. */
static int sk_sensitivity_full(const sk_mechanism *m, const double *inputs, const double *params,
                               int level, double *values, double *deviation, double *rigid)
{
    double theta[SK_M], delta[SK_K + 1], constants[SK_NQ];
    double dev[2 * SK_NP * SK_NV + 1], rig[2 * SK_NP * SK_NV + 1];
    const double *q;
    const sk_level *lv = sk_find_level(m, level);
    int i, v, status;
    if (params == NULL) {
        params = m->defaults;
    }
    status = deviation == NULL || inputs == NULL || lv == NULL
                 ? 3
                 : sk_pose(m, lv, inputs, params, 0, theta, delta, constants, &q);
    if (status == 0 && values != NULL) {
        status = sk_outputs(m, lv, theta, delta, params, q, values, NULL, NULL);
    }
    if (status == 0) {
        status = sk_sensitivity(m, lv, theta, delta, params, q, dev, rig);
    }
    for (i = 0; status == 0 && i < 2 * SK_NP * SK_NV; ++i) {
        if (!isfinite(dev[i]) || !isfinite(rig[i])) {
            status = 2;             /* a non-finite result is never a success */
        }
    }
    if (status != 0) {
        sk_nan(values, 6 * SK_NP);
        sk_nan(deviation, 2 * SK_NP * SK_NV);
        sk_nan(rigid, 2 * SK_NP * SK_NV);
        return status;
    }
    /* rows (point, component) x variables -> per point, per variable, dx then dy */
    for (i = 0; i < 2 * SK_NP; ++i) {
        for (v = 0; v < SK_NV; ++v) {
            deviation[((i / 2) * SK_NV + v) * 2 + i % 2] = dev[i * SK_NV + v];
            if (rigid != NULL) {
                rigid[((i / 2) * SK_NV + v) * 2 + i % 2] = rig[i * SK_NV + v];
            }
        }
    }
    return 0;
}

/* <name>_sensitivity: the parameters' columns of sk_sensitivity_full's deviation. */
static int sk_sensitivity_params(const sk_mechanism *m, const double *inputs,
                                 const double *params, int level, double *out)
{
    double full[2 * SK_NP * SK_NV + 1];
    int p, v, status;
    if (out == NULL) {
        return 3;
    }
    status = sk_sensitivity_full(m, inputs, params, level, NULL, full, NULL);
    for (p = 0; p < SK_NP; ++p) {
        for (v = 0; v < SK_NPAR; ++v) {
            out[(p * SK_NPAR + v) * 2] = full[(p * SK_NV + v) * 2];
            out[(p * SK_NPAR + v) * 2 + 1] = full[(p * SK_NV + v) * 2 + 1];
        }
    }
    return status;
}

/* <name>_sensitivity_batch: n rows; the number of rows that failed. */
static int sk_sensitivity_rows(const sk_mechanism *m, int n, const double *inputs,
                               const double *params, int level, double *values,
                               double *deviation, double *rigid, int *status)
{
    int j, s, failed = 0;
    for (j = 0; j < n; ++j) {
        s = inputs == NULL || deviation == NULL ? 3 : sk_sensitivity_full(
            m, inputs + (size_t)j * SK_NI, params, level,
            values == NULL ? NULL : values + (size_t)j * 6 * SK_NP,
            deviation + (size_t)j * 2 * SK_NP * SK_NV,
            rigid == NULL ? NULL : rigid + (size_t)j * 2 * SK_NP * SK_NV);
        failed += s != 0;
        if (status != NULL) {
            status[j] = s;
        }
    }
    return failed;
}
#endif
