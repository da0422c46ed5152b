/*
 * symkin's C runtime for the `loaded` level (docs/physics.md, "The Newton level"): the reduced
 * equilibrium of symkin.physics.reduced solved by Newton and continuation over the mechanism's
 * loaded_* routines, with the rules of the Python solver. Only evaluators that hold the level
 * hold it (templates/c/source.c.j2), after templates/c/runtime.c, whose sk_solve, sk_lu,
 * sk_lu_solve and sk_rigid_pose it calls; the generated file defines SK_RN (the largest number of
 * unknowns, and one), SK_RS (the most half plates, and one) and SK_RP (the points its deviation
 * routines give: every point of the file, the evaluator's first).
 */
#include <math.h>
#include <stddef.h>

/* ---- symkin runtime: every generated .c with the loaded level holds what follows ---- */

/* symkin reduced-equilibrium runtime (templates/c/reduced.c): Newton from x = 0 at load factor
   1, continuation in the inputs and loads together where Newton fails, the refusals (a plate at
   p_limit of its sway buckling load, the truncation estimate), two half plates per plate where
   one relation is refused by its estimate. */

typedef void (*sk_fn4)(const double *a, const double *b, const double *c, const double *d,
                       double *out);

/* One variant of the reduced equilibrium: `count` half plates per plate. */
typedef struct {
    int count;
    sk_fn3 plates;      /* (x, theta, params): per half plate (theta_c, p, f, e_a, e_s), then
                           d(theta_c, p, f)/dx (3 half plates x size) */
    sk_fn4 system;      /* (x, theta, plates, params): R, dR/dx, dR/d(plates) */
    sk_fn4 dev;         /* (x, theta, plates, params): every point's deviation */
    int size;           /* N: the scaled unknowns (x holds them, then the load factor t) */
    int plates_n;       /* half plates */
    const double *scale;
} sk_variant;

/* The loaded level's variants (one, two half plates per plate) and rules. */
typedef struct {
    sk_variant variants[2];
    int unknowns;       /* non-input hinges: x's first entries, delta / scale */
    double tol, max_turn, p_limit, est_factor, est_limit;
    int max_iter;
} sk_loaded;

/* One variant at one configuration. */
typedef struct {
    const sk_mechanism *m;
    const sk_loaded *l;
    const sk_variant *v;
    const double *params;
} sk_red;

/* The half plates' inputs (ins: 5 per half plate, then their x-Jacobian) and the plate relation
   at `order` (rel: 12 per half plate, values then partials) at (x, theta, t); xt: x, then t. */
static void sk_red_plates(const sk_red *r, const double *x, const double *theta, double t,
                          int order, double *xt, double *ins, double *rel)
{
    int i;
    for (i = 0; i < r->v->size; ++i) {
        xt[i] = x[i];
    }
    xt[r->v->size] = t;
    r->v->plates(xt, theta, r->params, ins);
    for (i = 0; i < r->v->plates_n; ++i) {
        if (order == 4) {
            sk_plate_relation4(ins + 5 * i, rel + 12 * i);
        } else {
            sk_plate_relation2(ins + 5 * i, rel + 12 * i);
        }
    }
}

/* The plates' values (along, across, omega), one after the other, from rel. */
static void sk_red_values(const sk_red *r, const double *rel, double *vals)
{
    int i, j;
    for (i = 0; i < r->v->plates_n; ++i) {
        for (j = 0; j < 3; ++j) {
            vals[3 * i + j] = rel[12 * i + j];
        }
    }
}

/* The residual R at `order` and, with jac not NULL, its Jacobian (order 4, n x n row-major):
   dR/dx + dR/d(plates) . the plates' partials . d(theta_c, p, f)/dx. */
static void sk_red_system(const sk_red *r, const double *x, const double *theta, double t,
                          int order, double *res, double *jac)
{
    const int n = r->v->size, ns = r->v->plates_n;
    double xt[SK_RN + 1], ins[SK_OUT], rel[12 * SK_RS], vals[3 * SK_RS], sys[SK_OUT];
    int i, j, k, c;
    sk_red_plates(r, x, theta, t, order, xt, ins, rel);
    sk_red_values(r, rel, vals);
    r->v->system(xt, theta, vals, r->params, sys);
    for (i = 0; i < n; ++i) {
        res[i] = sys[i];
    }
    if (jac == NULL) {
        return;
    }
    for (i = 0; i < n * n; ++i) {
        jac[i] = sys[n + i];
    }
    for (i = 0; i < n; ++i) {
        const double *jo = sys + n + n * n + i * 3 * ns;
        for (k = 0; k < ns; ++k) {
            const double *part = rel + 12 * k + 3, *din = ins + 5 * ns + 3 * k * n;
            double w[3];
            for (c = 0; c < 3; ++c) {
                w[c] = jo[3 * k] * part[c] + jo[3 * k + 1] * part[3 + c]
                       + jo[3 * k + 2] * part[6 + c];
            }
            for (j = 0; j < n; ++j) {
                jac[i * n + j] += w[0] * din[j] + w[1] * din[n + j] + w[2] * din[2 * n + j];
            }
        }
    }
}

/* The sign of det J at (x, theta, t): 1, -1, or NaN where J is singular or not finite. */
static double sk_red_sign(const sk_red *r, const double *x, const double *theta, double t)
{
    double res[SK_RN + 1], jac[SK_RN * SK_RN + 1], sign = 1.0;
    int piv[SK_RN + 1], i;
    const int n = r->v->size;
    sk_red_system(r, x, theta, t, 4, res, jac);
    if (sk_lu(n, jac, piv)) {
        return NAN;
    }
    for (i = 0; i < n; ++i) {
        if (jac[i * n + i] < 0.0) {
            sign = -sign;
        }
        if (piv[i] != i) {
            sign = -sign;
        }
    }
    return sign;
}

/* Newton from x at (theta, t): 0 converged, 1 not (a singular or non-finite Jacobian, a step
   turning a hinge by more than max_turn, a non-finite iterate, too many steps). */
static int sk_red_newton(const sk_red *r, double *x, const double *theta, double t)
{
    const int n = r->v->size, nu = r->l->unknowns;
    double res[SK_RN + 1], jac[SK_RN * SK_RN + 1], prev = HUGE_VAL;
    int it, i;
    for (it = 1; it <= r->l->max_iter; ++it) {
        double turn = 0.0, size = 0.0, top = 0.0;
        sk_red_system(r, x, theta, t, 4, res, jac);
        if (sk_solve(n, jac, 1, res)) {
            return 1;
        }
        for (i = 0; i < nu; ++i) {
            if (fabs(res[i]) > turn) {
                turn = fabs(res[i]);
            }
        }
        if (nu > 0 && turn * r->v->scale[0] > r->l->max_turn) {
            return 1;
        }
        for (i = 0; i < n; ++i) {
            x[i] -= res[i];
            if (!isfinite(x[i])) {
                return 1;
            }
            if (fabs(res[i]) > size) {
                size = fabs(res[i]);
            }
        }
        for (i = 0; i < n; ++i) {
            if (fabs(x[i]) > top) {
                top = fabs(x[i]);
            }
        }
        if (size <= r->l->tol * top || size == 0.0) {
            return 0;
        }
        if (it > 3 && size > 0.5 * prev && size < 1e-9 * top) {
            return 0;   /* stalled at rounding */
        }
        prev = size;
    }
    return 1;
}

/* A converged x on the branch followed: det J of the sign `sign`, every compliant angle within
   (-pi, pi). */
static int sk_red_accept(const sk_red *r, const double *x, const double *theta, double t,
                         double sign)
{
    int i;
    if (!(sk_red_sign(r, x, theta, t) == sign)) {
        return 0;
    }
    for (i = 0; i < SK_M; ++i) {
        double angle = theta[i];
        int j;
        for (j = 0; j < r->l->unknowns; ++j) {
            if (r->m->unknown_index[j] == i) {
                angle += x[j] * r->v->scale[j];
            }
        }
        if (!(fabs(angle) < 3.141592653589793)) {
            return 0;
        }
    }
    return 1;
}

/* The rigid angles at the inputs scaled by s into theta: 0, or a status where they cannot be
   reached. */
static int sk_red_rigid(const sk_mechanism *m, const double *inputs, const double *params,
                        double s, double *theta)
{
    double scaled[SK_NI + 1];
    int i;
    for (i = 0; i < SK_M; ++i) {
        theta[i] = 0.0;
    }
    for (i = 0; i < SK_NI; ++i) {
        scaled[i] = inputs[i] * s;
        theta[m->input_index[i]] = scaled[i];
    }
    for (i = 0; i < m->n_fixed; ++i) {
        theta[m->fixed_index[i]] = m->fixed_angle[i];
    }
#if defined(SK_LOOPS)
    return sk_rigid_pose(m, scaled, params, theta);
#else
    (void)params;
    return 0;
#endif
}

/* The deviation (dev: every point's) at the solution x and the refusals: 0, 1 a plate at
   p_limit of its sway buckling load (or J singular there), 4 the truncation estimate above
   est_limit. */
static int sk_red_answer(const sk_red *r, const double *x, const double *theta, double *dev)
{
    const int n = r->v->size, ns = r->v->plates_n;
    double xt[SK_RN + 1], ins[SK_OUT], rel[12 * SK_RS], vals[3 * SK_RS];
    double x2[SK_RN + 1], res[SK_RN + 1], jac[SK_RN * SK_RN + 1], dev2[2 * SK_RP + 1];
    double worst = 0.0, e24 = 0.0;
    const double count = r->v->count;
    int piv[SK_RN + 1], i;
    sk_red_plates(r, x, theta, 1.0, 4, xt, ins, rel);
    sk_red_values(r, rel, vals);
    r->v->dev(xt, theta, vals, r->params, dev);
    for (i = 0; i < ns; ++i) {
        const double p = ins[5 * i + 1], g = 1.0 + (ins[5 * i + 3] - ins[5 * i + 4]) * p;
        const double w = -g * p * count * count / (3.141592653589793 * 3.141592653589793);
        if (w > worst) {
            worst = w;
        }
    }
    /* the truncation estimate: one Newton step of the order-2 equations from the solution */
    for (i = 0; i < n; ++i) {
        x2[i] = x[i];
    }
    if (n > 0) {
        sk_red_system(r, x, theta, 1.0, 4, res, jac);
        sk_red_system(r, x, theta, 1.0, 2, res, NULL);
        if (sk_lu(n, jac, piv)) {
            return 1;
        }
        sk_lu_solve(n, jac, piv, res);
        for (i = 0; i < n; ++i) {
            x2[i] -= res[i];
        }
    }
    sk_red_plates(r, x2, theta, 1.0, 2, xt, ins, rel);
    sk_red_values(r, rel, vals);
    r->v->dev(xt, theta, vals, r->params, dev2);
    for (i = 0; i < SK_RP; ++i) {
        const double size = hypot(dev[2 * i], dev[2 * i + 1]);
        if (size > 0.0) {
            const double e = hypot(dev2[2 * i] - dev[2 * i], dev2[2 * i + 1] - dev[2 * i + 1]) / size;
            if (e > e24) {
                e24 = e;
            }
        }
    }
    if (worst >= r->l->p_limit) {
        return 1;
    }
    if (r->l->est_factor * e24 * e24 > r->l->est_limit) {
        return 4;
    }
    return 0;
}

/* One variant's solve (symkin.physics.reduced.Reduced.solve) into x and dev: 0, 1 refused, 2 no
   convergence, 4 refused by the truncation estimate. */
static int sk_red_solve(const sk_red *r, const double *inputs, const double *theta, double *x,
                        double *dev)
{
    const int n = r->v->size;
    double sign0;
    int i, ok;
    for (i = 0; i < n; ++i) {
        x[i] = 0.0;
    }
    if (n == 0) {
        return sk_red_answer(r, x, theta, dev);
    }
    sign0 = sk_red_sign(r, x, theta, 0.0);
    ok = !sk_red_newton(r, x, theta, 1.0) && sk_red_accept(r, x, theta, 1.0, sign0);
    if (!ok) {
        /* continuation: inputs and loads scaled together by s from the as-fabricated pose */
        double s = 0.0, ds = 0.25, sign, th_s[SK_M], th_1[SK_M], guess[SK_RN + 1];
        if (sk_red_rigid(r->m, inputs, r->params, 0.0, th_s)) {
            return 2;
        }
        for (i = 0; i < n; ++i) {
            x[i] = 0.0;
        }
        sign = sk_red_sign(r, x, th_s, 0.0);
        while (s < 1.0) {
            double s1;
            int good;
            if (ds < 1e-3) {
                return 2;
            }
            s1 = s + ds < 1.0 ? s + ds : 1.0;
            good = !sk_red_rigid(r->m, inputs, r->params, s1, th_1);
            if (good) {
                for (i = 0; i < n; ++i) {
                    guess[i] = x[i];
                }
                for (i = 0; i < r->l->unknowns; ++i) {
                    const int h = r->m->unknown_index[i];
                    guess[i] = (th_s[h] + x[i] * r->v->scale[i] - th_1[h]) / r->v->scale[i];
                }
                good = !sk_red_newton(r, guess, th_1, s1)
                       && sk_red_accept(r, guess, th_1, s1, sign);
            }
            if (good) {
                for (i = 0; i < n; ++i) {
                    x[i] = guess[i];
                }
                for (i = 0; i < SK_M; ++i) {
                    th_s[i] = th_1[i];
                }
                s = s1;
                ds = ds * 1.5 < 0.5 ? ds * 1.5 : 0.5;
            } else {
                ds /= 2.0;
            }
        }
    }
    return sk_red_answer(r, x, theta, dev);
}

/* The loaded level at one configuration (sk_mechanism.loaded_solve): theta holds the rigid
   angles; delta of the non-input hinges and q (the parameters, then the points' deviation) are
   written. Returns 0, 1 refused (a plate at p_limit of its sway buckling load, or the truncation
   estimate above est_limit with two half plates per plate), 2 no convergence. */
static int sk_reduced_pose(const void *mechanism, const double *inputs, const double *params,
                           const double *theta, double *delta, double *q)
{
    const sk_mechanism *m = (const sk_mechanism *)mechanism;
    const sk_loaded *l = (const sk_loaded *)m->loaded;
    double x[SK_RN + 1], dev[2 * SK_RP + 1];
    sk_red r;
    int v, i, status = 2;
    r.m = m;
    r.l = l;
    r.params = params;
    for (v = 0; v < 2; ++v) {
        r.v = l->variants + v;
        status = sk_red_solve(&r, inputs, theta, x, dev);
        if (status != 4) {
            break;
        }
    }
    if (status) {
        return status == 4 ? 1 : status;
    }
    for (i = 0; i < l->unknowns; ++i) {
        delta[i] = x[i] * r.v->scale[i];
    }
    for (i = 0; i < SK_NPAR; ++i) {
        q[i] = params[i];
    }
    for (i = 0; i < 2 * SK_NP; ++i) {
        q[SK_NPAR + i] = dev[i];
    }
    return 0;
}

/* The loaded level's deviation routine: the deviation sk_reduced_pose solved for, from q. */
static void sk_loaded_deviation(const double *theta, const double *delta, const double *q,
                                double *out)
{
    int i;
    (void)theta;
    (void)delta;
    for (i = 0; i < 2 * SK_NP; ++i) {
        out[i] = q[SK_NPAR + i];
    }
}
