/*
 * symkin's C runtime for the `loaded` level (docs/physics.md, "`loaded`: Newton on the reduced
 * equilibrium"): the reduced equilibrium of symkin.physics.reduced solved by Newton and
 * continuation over the mechanism's loaded_* routines, with the rules of the Python solver. Only
 * evaluators that hold the level hold it (templates/c/source.c.j2), after templates/c/runtime.c,
 * whose sk_lu, sk_lu_solve and sk_rigid_pose it calls; the generated file defines SK_RN (the
 * largest number of unknowns, and one), SK_RS (the most half plates, and one) and SK_RP (the points
 * its deviation routines give: every point of the file, the evaluator's first).
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
    sk_fn4 residual;    /* (x, theta, plates, params): R alone (chord steps, the estimate) */
    sk_fn4 dev;         /* (x, theta, plates, params): every point's deviation */
    int size;           /* N: the scaled unknowns (x holds them, then the load factor t) */
    int plates_n;       /* half plates */
    const double *scale;
} sk_variant;

/* The loaded level's variants (one, two half plates per plate); its rules are the generated
   file's SK_LOADED_* (symkin.core.settings.LoadedSettings). */
typedef struct {
    sk_variant variants[2];
    int unknowns;       /* non-input hinges: x's first entries, delta / scale */
    int loads;          /* the load factor t enters the routines (the file has loads) */
    double length;      /* the mechanism's size: the truncation estimate's floor is est_size
                           times it */
#if defined(SK_ACT_LOADED)
    const int *unknown_index;   /* theta index of the unknowns: the non-input hinges', then the
                                   actuators' surrogates' (docs/physics.md, "Actuators at
                                   loaded") */
#endif
} sk_loaded;

/* One variant at one configuration. */
typedef struct {
    const sk_mechanism *m;
    const sk_loaded *l;
    const sk_variant *v;
    const double *params;
} sk_red;

/* The half plates' inputs (ins: 5 per half plate, then their x-Jacobian) at (x, theta, t); xt:
   x, then t. */
static void sk_red_inputs(const sk_red *r, const double *x, const double *theta, double t,
                          double *xt, double *ins)
{
    int i;
    for (i = 0; i < r->v->size; ++i) {
        xt[i] = x[i];
    }
    xt[r->v->size] = t;
    r->v->plates(xt, theta, r->params, ins);
}

/* The plate relation at order 4 (rel: 12 per half plate, values then partials) of the inputs
   ins, and its values (along, across, omega), one half plate after the other, into vals. */
static void sk_red_relation(const sk_red *r, const double *ins, double *rel, double *vals)
{
    int i, j;
    for (i = 0; i < r->v->plates_n; ++i) {
        if (ins[5 * i + 1] == 0.0 && ins[5 * i + 2] == 0.0) {
            /* no force on the plate (x = 0 without loads, the unloaded state): the relation's
               few terms that remain */
            sk_plate_rest4(ins + 5 * i, rel + 12 * i);
        } else {
            sk_plate_relation4(ins + 5 * i, rel + 12 * i);
        }
        for (j = 0; j < 3; ++j) {
            vals[3 * i + j] = rel[12 * i + j];
        }
    }
}

/* The plate relation at order 4, its values alone (a chord step's), into vals. */
static void sk_red_values4(const sk_red *r, const double *ins, double *vals)
{
    int i, j;
    for (i = 0; i < r->v->plates_n; ++i) {
        if (ins[5 * i + 1] == 0.0 && ins[5 * i + 2] == 0.0) {
            double rest[12];
            sk_plate_rest4(ins + 5 * i, rest);
            for (j = 0; j < 3; ++j) {
                vals[3 * i + j] = rest[j];
            }
        } else {
            sk_plate_values4(ins + 5 * i, vals + 3 * i);
        }
    }
}

/* The plate relation at order 2, its values alone (the truncation estimate's), into vals. */
static void sk_red_values2(const sk_red *r, const double *ins, double *vals)
{
    int i;
    for (i = 0; i < r->v->plates_n; ++i) {
        sk_plate_values2(ins + 5 * i, vals + 3 * i);
    }
}

/* One evaluation of the system at order 4 (x, theta, t), kept for what follows it: the plates'
   inputs and relation, the system's output, J's LU and its determinant's sign. The last Newton
   step's J also gives the acceptance its sign and the truncation estimate its step (the Python
   solver's rule: J of the step that converged; here that of the last full step where chord
   steps followed it, its step below CHORD), and the last evaluation's plate values the
   solution's by one first-order correction (the step is below tol: the remainder is below
   rounding). */
typedef struct {
    double xt[SK_RN + 1], ins[SK_OUT], rel[12 * SK_RS], sys[SK_OUT], lu[SK_RN * SK_RN + 1];
    int piv[SK_RN + 1];
    double sign;  /* det J's: 1, -1, NaN where J is singular or not finite */
} sk_red_state;

/* st at (x, theta, t): 0, or 1 where J is singular or not finite (st->sign NaN). J = dR/dx +
   dR/d(plates) . the plates' partials . d(theta_c, p, f)/dx, n x n row-major. */
static int sk_red_eval(const sk_red *r, const double *x, const double *theta, double t,
                       sk_red_state *st)
{
    const int n = r->v->size, ns = r->v->plates_n;
    double vals[3 * SK_RS];
    double *jac = st->lu;
    int i, j, k, c;
    sk_red_inputs(r, x, theta, t, st->xt, st->ins);
    sk_red_relation(r, st->ins, st->rel, vals);
    r->v->system(st->xt, theta, vals, r->params, st->sys);
    for (i = 0; i < n * n; ++i) {
        jac[i] = st->sys[n + i];
    }
    for (i = 0; i < n; ++i) {
        const double *jo = st->sys + n + n * n + i * 3 * ns;
        for (k = 0; k < ns; ++k) {
            const double *part = st->rel + 12 * k + 3, *din = st->ins + 5 * ns + 3 * k * n;
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
    st->sign = NAN;
    if (sk_lu(n, jac, st->piv)) {
        return 1;
    }
    st->sign = 1.0;
    for (i = 0; i < n; ++i) {
        if (jac[i * n + i] < 0.0) {
            st->sign = -st->sign;
        }
        if (st->piv[i] != i) {
            st->sign = -st->sign;
        }
    }
    return 0;
}

/* A chord step's evaluation at (x, theta, t) into st: the plates' inputs, the relation's values
   (their partials and J's LU stay the last full step's) and R. */
static void sk_red_residual(const sk_red *r, const double *x, const double *theta, double t,
                            sk_red_state *st)
{
    double vals[3 * SK_RS];
    int i, j;
    sk_red_inputs(r, x, theta, t, st->xt, st->ins);
    sk_red_values4(r, st->ins, vals);
    for (i = 0; i < r->v->plates_n; ++i) {
        for (j = 0; j < 3; ++j) {
            st->rel[12 * i + j] = vals[3 * i + j];
        }
    }
    r->v->residual(st->xt, theta, vals, r->params, st->sys);
}

/* Newton from x at (theta, t): 0 converged, 1 not (a singular or non-finite Jacobian, a step
   turning a hinge by more than max_turn, a non-finite iterate, too many steps). After a step
   below chord times the largest unknown the next reuse its J (chord steps: R alone, J's
   partials move by about that step) while each shrinks tenfold. st: the last evaluation (J's
   that of the last full step); first: det J's sign at the first step (NaN where singular). */
static int sk_red_newton(const sk_red *r, double *x, const double *theta, double t,
                         sk_red_state *st, double *first)
{
    const int n = r->v->size, nu = r->l->unknowns;
    double res[SK_RN + 1], prev = HUGE_VAL;
    int it, i, chord = 0;
    *first = NAN;
    for (it = 1; it <= SK_LOADED_MAX_ITER; ++it) {
        double turn = 0.0, size = 0.0, top = 0.0;
        if (chord) {
            sk_red_residual(r, x, theta, t, st);
        } else {
            const int singular = sk_red_eval(r, x, theta, t, st);
            if (it == 1) {
                *first = st->sign;
            }
            if (singular) {
                return 1;
            }
        }
        /* sk_lu then sk_lu_solve: sk_solve's operations, the factors kept */
        for (i = 0; i < n; ++i) {
            res[i] = st->sys[i];
        }
        sk_lu_solve(n, st->lu, st->piv, res);
        for (i = 0; i < nu; ++i) {
            if (fabs(res[i]) > turn) {
                turn = fabs(res[i]);
            }
        }
        if (nu > 0 && turn * r->v->scale[0] > SK_LOADED_MAX_TURN) {
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
        /* a Newton step leaves about its square, below rounding; a chord step its size times
           the contraction (size / prev) */
        if (size == 0.0
            || (size <= SK_LOADED_TOL * top
                && (!chord || size * size <= SK_LOADED_CHORD_ERROR * top * prev))) {
            return 0;
        }
        if (!chord && it > SK_LOADED_STALL_AFTER && size > SK_LOADED_STALL_RATIO * prev
            && size < SK_LOADED_STALLED * top) {
            return 0;   /* stalled at rounding (a full step's: a chord step's is its J's) */
        }
        chord = size <= SK_LOADED_CHORD * top && (!chord || size <= SK_LOADED_CHORD_SHRINK * prev);
        prev = size;
    }
    return 1;
}

/* A converged x on the branch followed: det J of the sign `sign` (J of the last Newton step,
   st), every compliant angle within (-pi, pi). */
static int sk_red_accept(const sk_red *r, const double *x, const double *theta,
                         const sk_red_state *st, double sign)
{
    int i;
    if (!(st->sign == sign)) {
        return 0;
    }
    for (i = 0; i < SK_M; ++i) {
        double angle = theta[i];
        int j;
        for (j = 0; j < r->l->unknowns; ++j) {
#if defined(SK_ACT_LOADED)
            if (r->l->unknown_index[j] == i) {
#else
            if (r->m->unknown_index[j] == i) {
#endif
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
    double scaled[SK_NI + 1] = {0.0};
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
   p_limit of its sway buckling load, 4 the truncation estimate above est_limit. st: the last
   Newton step's evaluation at (theta, 1), a step below tol from x (NULL where x has no entries);
   its J that of the last full step. */
static int sk_red_answer(const sk_red *r, const double *x, const double *theta,
                         const sk_red_state *st, double *dev)
{
    const int n = r->v->size, ns = r->v->plates_n;
    double xt[SK_RN + 1], ins[SK_OUT], rel[12 * SK_RS], vals[3 * SK_RS], sys[SK_OUT];
    double x2[SK_RN + 1], res[SK_RN + 1], dev2[2 * SK_RP + 1];
    double worst = 0.0, e24 = 0.0, least = 0.0;
    const double count = r->v->count;
    int i, j;
    sk_red_inputs(r, x, theta, 1.0, xt, ins);
    if (st == NULL) {
        sk_red_relation(r, ins, rel, vals);
    } else {
        /* the plate relation at x from st's by its partials: x moved by the last step only,
           below tol, so the remainder (its square) is below rounding */
        for (i = 0; i < ns; ++i) {
            const double *at = st->rel + 12 * i, *part = at + 3;
            const double d0 = ins[5 * i] - st->ins[5 * i], d1 = ins[5 * i + 1] - st->ins[5 * i + 1];
            const double d2 = ins[5 * i + 2] - st->ins[5 * i + 2];
            for (j = 0; j < 3; ++j) {
                vals[3 * i + j] = at[j] + (part[3 * j] * d0 + part[3 * j + 1] * d1
                                           + part[3 * j + 2] * d2);
            }
        }
    }
    r->v->dev(xt, theta, vals, r->params, dev);
    for (i = 0; i < ns; ++i) {
        const double p = ins[5 * i + 1], g = 1.0 + (ins[5 * i + 3] - ins[5 * i + 4]) * p;
        const double w = -g * p * count * count / (3.141592653589793 * 3.141592653589793);
        if (w > worst) {
            worst = w;
        }
    }
    /* the truncation estimate: one Newton step of the order-2 equations from the solution, with
       the last Newton step's J (its LU, st) */
    for (i = 0; i < n; ++i) {
        x2[i] = x[i];
    }
    if (n > 0) {
        sk_red_values2(r, ins, vals);
        r->v->residual(xt, theta, vals, r->params, sys);
        for (i = 0; i < n; ++i) {
            res[i] = sys[i];
        }
        sk_lu_solve(n, st->lu, st->piv, res);
        for (i = 0; i < n; ++i) {
            x2[i] -= res[i];
        }
    }
    sk_red_inputs(r, x2, theta, 1.0, xt, ins);
    sk_red_values2(r, ins, vals);
    r->v->dev(xt, theta, vals, r->params, dev2);
    /* each point's change against its deviation, at least est_share of the largest one and
       est_size times the mechanism's size (symkin.physics.reduced_solver's _red_verdict) */
    for (i = 0; i < SK_RP; ++i) {
        const double size = hypot(dev[2 * i], dev[2 * i + 1]);
        if (size > least) {
            least = size;
        }
    }
    least *= SK_LOADED_EST_SHARE;
    if (SK_LOADED_EST_SIZE * r->l->length > least) {
        least = SK_LOADED_EST_SIZE * r->l->length;
    }
    for (i = 0; i < SK_RP; ++i) {
        const double own = hypot(dev[2 * i], dev[2 * i + 1]), size = own > least ? own : least;
        if (size > 0.0) {
            const double e = hypot(dev2[2 * i] - dev[2 * i], dev2[2 * i + 1] - dev[2 * i + 1]) / size;
            if (e > e24) {
                e24 = e;
            }
        }
    }
    if (worst >= SK_LOADED_P_LIMIT) {
        return 1;
    }
    if (SK_LOADED_EST_FACTOR * e24 * e24 > SK_LOADED_EST_LIMIT) {
        return 4;
    }
    return 0;
}

/* One variant's solve (symkin.physics.reduced_solver's _red_equilibrium) into x and dev: 0, 1
   refused, 2 no convergence, 4 refused by the truncation estimate. */
static int sk_red_solve(const sk_red *r, const double *inputs, const double *theta, double *x,
                        double *dev)
{
    const int n = r->v->size;
    sk_red_state st;
    double sign0, first;
    int i, ok;
    for (i = 0; i < n; ++i) {
        x[i] = 0.0;
    }
    if (n == 0) {
        return sk_red_answer(r, x, theta, NULL, dev);
    }
    /* det J's sign at the unloaded state (x = 0, t = 0): without loads t enters nowhere and it
       is the first Newton step's (the same J), else one evaluation of its own */
    sign0 = NAN;
    if (r->l->loads) {
        sk_red_eval(r, x, theta, 0.0, &st);
        sign0 = st.sign;
    }
    ok = !sk_red_newton(r, x, theta, 1.0, &st, &first);
    if (!r->l->loads) {
        sign0 = first;
    }
    ok = ok && sk_red_accept(r, x, theta, &st, sign0);
    if (!ok) {
        /* continuation: inputs and loads scaled together by s from the as-fabricated pose */
#if defined(SK_ACT_FORCES)
        /* the force actuators' forces after the rigid angles, kept at every step (t scales
           them with the loads) */
        double s = 0.0, ds = SK_LOADED_FIRST_STEP, sign, th_s[SK_M + SK_NF], th_1[SK_M + SK_NF], guess[SK_RN + 1];
        for (i = SK_M; i < SK_M + SK_NF; ++i) {
            th_s[i] = theta[i];
            th_1[i] = theta[i];
        }
#else
        double s = 0.0, ds = SK_LOADED_FIRST_STEP, sign, th_s[SK_M], th_1[SK_M], guess[SK_RN + 1];
#endif
        if (sk_red_rigid(r->m, inputs, r->params, 0.0, th_s)) {
            return 2;
        }
        for (i = 0; i < n; ++i) {
            x[i] = 0.0;
        }
        sk_red_eval(r, x, th_s, 0.0, &st);
        sign = st.sign;
        while (s < 1.0) {
            double s1;
            int good = 1;
            if (ds < SK_LOADED_SMALLEST_STEP) {
                return 2;
            }
            s1 = s + ds < 1.0 ? s + ds : 1.0;
            if (s1 == 1.0) {
                /* the configuration's own rigid angles: the answer reads the last step's J */
                for (i = 0; i < SK_M; ++i) {
                    th_1[i] = theta[i];
                }
            } else {
                good = !sk_red_rigid(r->m, inputs, r->params, s1, th_1);
            }
            if (good) {
                for (i = 0; i < n; ++i) {
                    guess[i] = x[i];
                }
                for (i = 0; i < r->l->unknowns; ++i) {
#if defined(SK_ACT_LOADED)
                    const int h = r->l->unknown_index[i];
#else
                    const int h = r->m->unknown_index[i];
#endif
                    guess[i] = (th_s[h] + x[i] * r->v->scale[i] - th_1[h]) / r->v->scale[i];
                }
                good = !sk_red_newton(r, guess, th_1, s1, &st, &first)
                       && sk_red_accept(r, guess, th_1, &st, sign);
            }
            if (good) {
                for (i = 0; i < n; ++i) {
                    x[i] = guess[i];
                }
                for (i = 0; i < SK_M; ++i) {
                    th_s[i] = th_1[i];
                }
                s = s1;
                ds = ds * SK_LOADED_STEP_GROWTH < SK_LOADED_LARGEST_STEP
                         ? ds * SK_LOADED_STEP_GROWTH
                         : SK_LOADED_LARGEST_STEP;
            } else {
                ds *= SK_LOADED_STEP_CUT;
            }
        }
    }
    return sk_red_answer(r, x, theta, &st, dev);
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
#if defined(SK_ACT_LOADED)
    for (i = 0; i < SK_K; ++i) { /* the surrogates' turn: in q's x */
#else
    for (i = 0; i < l->unknowns; ++i) {
#endif
        delta[i] = x[i] * r.v->scale[i];
    }
    for (i = 0; i < SK_NPAR; ++i) {
        q[i] = params[i];
    }
    for (i = 0; i < 2 * SK_NP; ++i) {
        q[SK_NPAR + i] = dev[i];
    }
    /* the variant and its solution, for the sensitivities (templates/c/reduced_sens.c) */
    q[SK_NPAR + 2 * SK_NP] = v;
    for (i = 0; i < r.v->size; ++i) {
        q[SK_NPAR + 2 * SK_NP + 1 + i] = x[i];
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
#if defined(SK_LOADED_IFT)

/* The solution q holds (the parameters, the deviation, the variant solved and its x,
   sk_reduced_pose) evaluated again for the implicit-function theorem (templates/c/
   reduced_sens.c, reduced_report.c): r its variant at the parameters, st J's LU, the plates'
   inputs and relation and the system's output there, vals the relation's values per half plate.
   Returns 0, or 1 where J is singular. */
static int sk_red_at_solution(const sk_mechanism *m, const double *theta, const double *q,
                              sk_red *r, sk_red_state *st, double *vals)
{
    const sk_loaded *l = (const sk_loaded *)m->loaded;
    const double *x = q + SK_NPAR + 2 * SK_NP + 1;
    int n, i, k, c;
    r->m = m;
    r->l = l;
    r->v = l->variants + (int)q[SK_NPAR + 2 * SK_NP];
    r->params = q;
    n = r->v->size;
    if (n > 0 && sk_red_eval(r, x, theta, 1.0, st)) {
        return 1;
    }
    if (n == 0) {
        double rel[12 * SK_RS];
        sk_red_inputs(r, x, theta, 1.0, st->xt, st->ins);
        sk_red_relation(r, st->ins, rel, vals);
        for (i = 0; i < 12 * r->v->plates_n; ++i) {
            st->rel[i] = rel[i];
        }
    }
    for (k = 0; k < r->v->plates_n; ++k) {
        for (c = 0; c < 3; ++c) {
            vals[3 * k + c] = st->rel[12 * k + c];
        }
    }
    return 0;
}
#endif
