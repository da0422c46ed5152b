/*
 * symkin's C runtime for actuators (docs/levels.md, "Actuators"): what a generated evaluator of
 * a mechanism with actuators runs around templates/c/runtime.c's sk_evaluate_pose (and at loaded,
 * SK_ACT_LOADED, around templates/c/reduced.c). Only those evaluators hold it
 * (templates/c/source.c.j2), after the runtime; it reads the same sizes (SK_M, SK_NI, SK_NP,
 * SK_NL; SK_NF with force actuators, SK_ACT_FORCES) and the tables of one sk_actuators.
 */
#include <math.h>
#include <stddef.h>

/* ---- symkin runtime: every generated .c holds what follows ---- */

/* symkin actuators runtime (templates/c/actuators.c): the strokes to the surrogate hinges'
   angles, twice (the rigid linkage, then the compliant mechanism from there), the answer the
   solves' last evaluations; at loaded once (the rigid linkage), the reduced equilibrium there,
   the surrogates free, a force actuator's rigid reference again at the stroke it produced. */

/* The actuators of a mechanism: for every kinematic input (an input angle of sk_evaluate_pose)
   the position of its value among the public inputs, or -1 - a for the surrogate hinge of
   actuator a; per actuator its point (among the SK_NP points), its stroke's position among the
   public inputs and its direction; the points the public functions report (with force
   actuators, which drive the loaded level alone, what each one's value is). */
typedef struct {
    int n;
    const int *drive_of;
    const int *point;
    const int *stroke;
    const double *direction;
    /* the points of action as fabricated from the parameters (2 per actuator): where each
       stroke is measured from, whatever inputs the evaluator holds fixed (derive --fix) */
    void (*action_at)(const double *params, double *out);
    int n_shown;
    const int *shown;
#if defined(SK_ACT_FORCES)
    const int *force;   /* per actuator: its force's place after the rigid angles in the loaded
                           routines' theta, or -1 (a stroke; docs/physics.md) */
#endif
#if defined(SK_ACT_SPRINGS)
    const int *spring;  /* per actuator: 1 where a series spring makes the reported stroke the
                           actual one, the command less force/spring (docs/physics.md) */
#endif
} sk_actuators;

/* Gaussian elimination with partial pivoting of the n x n row-major a (destroyed) for the
   n x m row-major right-hand sides b, which become the solution (the runtime's sk_solve is only
   there when the mechanism has loops). Returns 0, or 1 when a pivot is zero or not finite. */
static int sk_act_solve(int n, double *a, int m, double *b)
{
    int i, j, c, p;
    double f;
    for (c = 0; c < n; ++c) {
        for (p = c, i = c + 1; i < n; ++i) {
            p = fabs(a[i * n + c]) > fabs(a[p * n + c]) ? i : p;
        }
        if (!(fabs(a[p * n + c]) > 0.0) || !isfinite(a[p * n + c])) {
            return 1;
        }
        for (j = 0; j < n; ++j) {
            f = a[c * n + j];
            a[c * n + j] = a[p * n + j];
            a[p * n + j] = f;
        }
        for (j = 0; j < m; ++j) {
            f = b[c * m + j];
            b[c * m + j] = b[p * m + j];
            b[p * m + j] = f;
        }
        for (i = c + 1; i < n; ++i) {
            f = a[i * n + c] / a[c * n + c];
            for (j = c; j < n; ++j) {
                a[i * n + j] -= f * a[c * n + j];
            }
            for (j = 0; j < m; ++j) {
                b[i * m + j] -= f * b[c * m + j];
            }
        }
    }
    for (c = n - 1; c >= 0; --c) {
        for (j = 0; j < m; ++j) {
            for (i = c + 1; i < n; ++i) {
                b[c * m + j] -= a[c * n + i] * b[i * m + j];
            }
            b[c * m + j] /= a[c * n + c];
        }
    }
    return 0;
}

/* The points (out: 6 per point) and angles (2 SK_M, or NULL) at the kinematic inputs x at
   `level` (sk_evaluate_pose); at level -1 (SK_LEVEL_RIGID of an evaluator whose only level is
   loaded, as a file with a force actuator's) the rigid linkage alone: each point's rigid x, y
   (the rest NaN) and the rigid angles (angles' first SK_M entries). Returns a status code. */
static int sk_stroke_pose(const sk_mechanism *m, const double *x, const double *params, int level,
                          double *out, double *angles)
{
#if defined(SK_ACT_LOADED)
    if (level < 0) {
        double theta[SK_M], rigid[2 * SK_NP + 1];
        int i, s;
        for (i = 0; i < SK_NI; ++i) {
            if (!isfinite(x[i]) || !(fabs(x[i]) <= 3.141592653589793)) {
                return 3;
            }
        }
        s = sk_red_rigid(m, x, params == NULL ? m->defaults : params, 1.0, theta);
        if (s == 0) {
            m->rigid_points(theta, params == NULL ? m->defaults : params, rigid);
        }
        for (i = 0; i < 2 * SK_NP && s == 0; ++i) {
            s = isfinite(rigid[i]) ? 0 : 2;
        }
        sk_nan(out, 6 * SK_NP);
        sk_nan(angles, SK_M);
        for (i = 0; i < SK_NP && s == 0; ++i) {
            out[6 * i] = rigid[2 * i];
            out[6 * i + 1] = rigid[2 * i + 1];
        }
        for (i = 0; angles != NULL && i < SK_M && s == 0; ++i) {
            angles[i] = theta[i];
        }
        return s;
    }
#endif
    return sk_evaluate_pose(m, x, params, level, out, angles, NULL);
}

/* The rigid linkage alone at the kinematic inputs x (each point's rigid x, y into out, 6 per
   point, the rest unset; the rigid angles into theta): sk_pose without a level's closure, then
   the rigid points, so the same numbers as sk_evaluate_pose's rigid ones at any kinematic level
   without solving the loops for delta. Returns a status code. */
static int sk_stroke_rigid_points(const sk_mechanism *m, const double *x, const double *params,
                                  double *out, double *theta)
{
    static const sk_level rigid_only = {0, NULL, NULL, NULL, 0, {NULL, 0, 0, 0, 0, 0, 0, 0},
                                        NULL, NULL};
    double delta[SK_K + 1], constants[SK_NQ], rigid[2 * SK_NP + 1];
    const double *q;
    int i, s;
    if (params == NULL) {
        params = m->defaults;
    }
    s = sk_pose(m, &rigid_only, x, params, 0, theta, delta, constants, &q);
    if (s == 0) {
        m->rigid_points(theta, params, rigid);
    }
    for (i = 0; i < SK_NP && s == 0; ++i) {
        s = isfinite(rigid[2 * i]) && isfinite(rigid[2 * i + 1]) ? 0 : 2;
        out[6 * i] = rigid[2 * i];
        out[6 * i + 1] = rigid[2 * i + 1];
    }
    return s;
}

/* One evaluation of a stroke solve, kept for the answer: points (kind 0: rigid x, y alone),
   angles (kind 0: the rigid ones) and, kind 1 when asked, links, laid out as sk_outputs'. */
typedef struct {
    double out[6 * SK_NP];
    double angles[2 * SK_M];
    double links[3 * SK_NL + 1];
} sk_stroke_at;

/* Each actuator's stroke residual d.(X - X0) - s at the kinematic inputs x: X the rigid
   (kind 0: the rigid linkage alone at a kinematic level, sk_stroke_rigid_points) or compliant
   (kind 1, the links too with want_links) position of its point; what it evaluated into at.
   Returns the evaluation's status. */
static int sk_stroke_residual(const sk_mechanism *m, const sk_actuators *t, const double *x,
                              const double *params, int level, int kind, int want_links,
                              const double *rest, const double *drives, double *r,
                              sk_stroke_at *at)
{
    int a, s = kind == 0 && level >= 0
                   ? sk_stroke_rigid_points(m, x, params, at->out, at->angles)
               : kind == 0 ? sk_stroke_pose(m, x, params, level, at->out, at->angles)
                           : sk_evaluate_pose(m, x, params, level, at->out, at->angles,
                                              want_links ? at->links : NULL);
    for (a = 0; a < t->n && s == 0; ++a) {
        const double *p = at->out + 6 * t->point[a] + 2 * kind;
        const double *p0 = rest + 2 * a;
        r[a] = t->direction[2 * a] * (p[0] - p0[0]) + t->direction[2 * a + 1] * (p[1] - p0[1])
               - drives[t->stroke[a]];
    }
    return s;
}

/* A stroke solve's Jacobian (n x n, row-major) for the next, and whether it holds one. */
typedef struct {
    double jac[(SK_NI + 1) * (SK_NI + 1)];
    int have;
} sk_stroke_jac;

/* Newton's method on the strokes in the surrogates' angles of x (in place), its Jacobian j the
   same point's earlier solve's (the rigid linkage's for the compliant mechanism's: they differ
   by the compliance alone) or by forward differences at x, then Broyden (secant) updates: a step
   costs one evaluation. A fresh Jacobian where an updated one is singular or its step does not
   shrink the residual to SK_STROKE_SECANT of it; a fresh one's step halved while it leaves the
   assembly range or grows the residual; once met, one more step while above SK_STROKE_POLISH.
   No state outside the point. Returns 0 when every stroke is met to `tol`, the last evaluation
   in `keep` (at x), else 1 (or the evaluator's status). */
static int sk_stroke_solve(const sk_mechanism *m, const sk_actuators *t, double *x,
                           const double *params, int level, int kind, int want_links,
                           const double *rest, const double *drives, double tol,
                           sk_stroke_jac *j, sk_stroke_at *keep)
{
    double r[SK_NI + 1], trial[SK_NI + 1], lu[(SK_NI + 1) * (SK_NI + 1)], up[SK_NI + 1];
    double move[SK_NI + 1], size = 0.0, next = 0.0, dd;
    const double fine = tol * (SK_STROKE_POLISH / SK_STROKE_TOLERANCE);
    sk_stroke_at spare, *cur = keep, *other = &spare, *swap;
    int where[SK_NI + 1];
    int i, k, iter, half, s, fresh, met, ok, n = t->n;
    for (k = 0; k < SK_NI; ++k) {
        if (t->drive_of[k] < 0) {
            where[-1 - t->drive_of[k]] = k;
        }
    }
    s = sk_stroke_residual(m, t, x, params, level, kind, want_links, rest, drives, r, cur);
    for (iter = 0; s == 0 && iter < SK_STROKE_ITERATIONS; ++iter) {
        for (size = 0.0, i = 0; i < n; ++i) {
            size = fabs(r[i]) > size ? fabs(r[i]) : size;
        }
        /* met: one more step while above the rounding (a secant's last step leaves more than
           Newton's), kept where it shrinks the residual */
        met = !(size > tol);
        if (met && !(size > fine && j->have)) {
            break;
        }
        fresh = !j->have;
        for (k = 0; fresh && s == 0 && k < n; ++k) {
            for (i = 0; i < SK_NI; ++i) {
                trial[i] = x[i];
            }
            trial[where[k]] = x[where[k]] + SK_STROKE_STEP; /* sqrt(eps) */
            s = sk_stroke_residual(m, t, trial, params, level, kind, want_links, rest, drives,
                                   up, other);
            for (i = 0; i < n && s == 0; ++i) {
                j->jac[i * n + k] = (up[i] - r[i]) / SK_STROKE_STEP;
            }
        }
        if (s != 0) {
            break;
        }
        for (i = 0; i < n * n; ++i) {
            lu[i] = j->jac[i];
        }
        for (i = 0; i < n; ++i) {
            move[i] = r[i];
        }
        j->have = sk_act_solve(n, lu, 1, move) == 0;
        for (half = 0, ok = 0; j->have && half < SK_STROKE_HALVINGS; ++half) {
            for (i = 0; i < SK_NI; ++i) {
                trial[i] = x[i];
            }
            for (k = 0; k < n; ++k) {
                trial[where[k]] -= move[k];
            }
            s = sk_stroke_residual(m, t, trial, params, level, kind, want_links, rest, drives,
                                   up, other);
            for (next = 0.0, i = 0; i < n && s == 0; ++i) {
                next = fabs(up[i]) > next ? fabs(up[i]) : next;
            }
            ok = s == 0 && (fresh || met ? next < size : next <= SK_STROKE_SECANT * size);
            if (ok || !fresh || met) {
                break; /* an updated Jacobian's step is not halved: a fresh one instead */
            }
            for (k = 0; k < n; ++k) {
                move[k] *= SK_STROKE_CUT;
            }
        }
        s = 0;
        if (met || (!ok && fresh)) {
            for (i = 0; met && ok && i < SK_NI; ++i) {
                x[i] = trial[i];
            }
            cur = met && ok ? other : cur;
            s = met ? 0 : 1;
            break;
        }
        if (!ok) {
            j->have = 0;
            continue;
        }
        /* Broyden: J += (dr - J dx) dx' / (dx' dx), dx = -move, dr = up - r */
        for (dd = 0.0, k = 0; k < n; ++k) {
            dd += move[k] * move[k];
        }
        for (i = 0; i < n && dd > 0.0; ++i) {
            double miss = up[i] - r[i];
            for (k = 0; k < n; ++k) {
                miss += j->jac[i * n + k] * move[k];
            }
            for (k = 0; k < n; ++k) {
                j->jac[i * n + k] -= miss * move[k] / dd;
            }
        }
        for (i = 0; i < n; ++i) {
            r[i] = up[i];
        }
        swap = cur;
        cur = other;
        other = swap;
        for (i = 0; i < SK_NI; ++i) {
            x[i] = trial[i];
        }
    }
    if (s == 0 && cur != keep) {
        *keep = *cur;
    }
    return s != 0 ? s : iter == SK_STROKE_ITERATIONS || !isfinite(size) ? 1 : 0;
}

/* The tolerance of the stroke solves: SK_STROKE_TOLERANCE (64 eps) times the largest coordinate
   of the points of action as fabricated (`rest`, 2 per actuator), that at least
   SK_STROKE_FLOOR. */
static double sk_stroke_tol(const sk_actuators *t, const double *rest)
{
    double scale = SK_STROKE_FLOOR;
    int i;
    for (i = 0; i < t->n; ++i) {
        const double *p0 = rest + 2 * i;
        scale = fabs(p0[0]) > scale ? fabs(p0[0]) : scale;
        scale = fabs(p0[1]) > scale ? fabs(p0[1]) : scale;
    }
    return SK_STROKE_TOLERANCE * scale;
}

/* The kinematic inputs xr at which the rigid linkage (the rigid positions of `level`) meets the
   strokes among the public inputs `drives`; `rest` (2 per actuator) gets the points of action
   as fabricated (t->action_at: from the parameters, not the pose at zero inputs, which a fixed
   input would move); j the solve's last Jacobian, er its rigid points and angles at xr. Returns
   0, 3 where a public input or a point of action is not finite (a NaN stroke would pass the
   stroke solve's test), or the status of what failed. */
static int sk_stroke_rigid(const sk_mechanism *m, const sk_actuators *t, const double *drives,
                           const double *params, int level, double *xr, double *rest,
                           sk_stroke_jac *j, sk_stroke_at *er)
{
    int k;
    for (k = 0; k < SK_NI; ++k) {
        if (!isfinite(drives[k])) {
            return 3;
        }
    }
    t->action_at(params == NULL ? m->defaults : params, rest);
    for (k = 0; k < 2 * t->n; ++k) {
        if (!isfinite(rest[k])) {
            return 3;
        }
    }
    for (k = 0; k < SK_NI; ++k) {
        xr[k] = t->drive_of[k] >= 0 ? drives[t->drive_of[k]] : 0.0;
    }
    j->have = 0;
    return sk_stroke_solve(m, t, xr, params, level, 0, 0, rest, drives, sk_stroke_tol(t, rest), j,
                           er);
}

/* The kinematic inputs at which the rigid linkage (xr) and the compliant mechanism at `level`
   (xc) meet the strokes among the public inputs `drives` (docs/levels.md, "Actuators"); `rest`
   (2 per actuator) the points of action as fabricated; er the rigid points and angles at xr, ec
   the evaluation at xc (its links with want_links). The compliant solve starts from the rigid
   one's pose and Jacobian. Returns 0, or the status of what failed. */
static int sk_stroke_poses(const sk_mechanism *m, const sk_actuators *t, const double *drives,
                           const double *params, int level, double *xr, double *xc,
                           double *rest, sk_stroke_at *er, sk_stroke_at *ec, int want_links)
{
    sk_stroke_jac jac;
    int k, s = sk_stroke_rigid(m, t, drives, params, level, xr, rest, &jac, er);
    for (k = 0; k < SK_NI; ++k) {
        xc[k] = xr[k];
    }
    return s != 0 ? s
                  : sk_stroke_solve(m, t, xc, params, level, 1, want_links, rest, drives,
                                    sk_stroke_tol(t, rest), &jac, ec);
}

/* The rigid linkage and the compliant mechanism at `level` at the strokes (docs/levels.md,
   "Actuators"), combined as sk_outputs lays them out (pr: 6 per point, ar: 2 SK_M, lr: 3 SK_NL
   or NULL): the rigid linkage at the surrogates' rigid angles, the compliant mechanism at their
   compliant ones, the deviation the rigid motion between the two plus the level's deviation at
   the compliant angles. The solves' last evaluations are the answer's: nothing is evaluated
   twice. Returns 0, or the status of what failed. */
static int sk_actuated_kinematic(const sk_mechanism *m, const sk_actuators *t,
                                 const double *drives, const double *params, int level,
                                 double *pr, double *ar, double *lr)
{
    double rest[2 * SK_NI], xr[SK_NI + 1], xc[SK_NI + 1];
    sk_stroke_at er, ec;
    int i, j, s;
    s = sk_stroke_poses(m, t, drives, params, level, xr, xc, rest, &er, &ec, lr != NULL);
    for (i = 0; i < SK_NP && s == 0; ++i) {
        double *r = pr + 6 * i;
        const double *c = ec.out + 6 * i;
        r[0] = er.out[6 * i];
        r[1] = er.out[6 * i + 1];
        for (j = 0; j < 2; ++j) {
            r[2 + j] = c[2 + j];
            r[4 + j] = c[j] - r[j] + c[4 + j];
        }
    }
    for (j = 0; j < SK_M && s == 0; ++j) {
        ar[j] = er.angles[j];
        ar[SK_M + j] = ec.angles[SK_M + j];
    }
#if defined(SK_LINKS)
    if (lr != NULL && s == 0) { /* the rigid rotations at the rigid angles: no delta read */
        double rot[2 * SK_NL + 1], zero[SK_K + 1];
        for (j = 0; j < SK_K + 1; ++j) {
            zero[j] = 0.0;
        }
        m->links(er.angles, zero, rot);
        for (j = 0; j < SK_NL && s == 0; ++j) {
            s = isfinite(rot[j]) ? 0 : 2;
            lr[3 * j] = sk_wrap(rot[j]);
            lr[3 * j + 1] = ec.links[3 * j + 1];
            lr[3 * j + 2] = ec.links[3 * j] - lr[3 * j] + ec.links[3 * j + 2];
        }
    }
#endif
    return s;
}
#if defined(SK_ACT_LOADED)
/* The loaded level's solution with actuators (sk_actuated_loaded): the loaded routines' theta
   (the rigid angles at the strokes, then the forces) and q, what the level's routines read
   (the parameters, the deviation, the variant solved and its x; written into `constants`), for
   what the level reports there (sk_actuated_report). */
typedef struct {
#if defined(SK_ACT_FORCES)
    double theta[SK_M + SK_NF];
#else
    double theta[SK_M];
#endif
    double constants[SK_NQ];
    const double *q;
} sk_act_solution;

#if defined(SK_ACT_FORCES)
/* The public inputs of the first solve (strokes: a force actuator's stroke 0, against the
   as-fabricated pose) and the forces after the rigid angles in theta, where the loaded routines
   read them. Returns 0, or 3 where a force is not finite. */
static int sk_force_split(const sk_actuators *t, const double *drives, double *strokes,
                          double *theta)
{
    int a, j;
    for (j = 0; j < SK_NI; ++j) {
        strokes[j] = drives[j];
    }
    for (a = 0; a < t->n; ++a) {
        if (t->force[a] >= 0) {
            theta[SK_M + t->force[a]] = drives[t->stroke[a]];
            strokes[t->stroke[a]] = 0.0;
            if (!isfinite(drives[t->stroke[a]])) {
                return 3;
            }
        }
    }
    return 0;
}

/* A force actuator's rigid reference (docs/physics.md, "Actuators at loaded"): xr solved again,
   from the first solve's, for the rigid linkage at the stroke each force produced (its point of
   action's compliant place along d from as fabricated, rest); the points' rigid positions and
   deviations (pr) and the rigid angles (ar) become the reference's, the compliant ones stay (the
   compliant pose does not depend on the reference). Returns 0, or 4 where no pose of the rigid
   linkage reaches the stroke a force produced (docs/physics.md, "Beyond the rigid reach"): the
   rigid positions and deviations NaN, the compliant ones kept, ar's rigid angles those of the
   first solve (the caller makes them NaN). */
static int sk_force_reference(const sk_mechanism *m, const sk_actuators *t,
                              const double *strokes, const double *params, const double *rest,
                              sk_stroke_jac *jac, double *xr, double *pr, double *ar)
{
    double produced[SK_NI + 1], *ref;
    sk_stroke_at at;
    int a, i, j, s;
    for (j = 0; j < SK_NI; ++j) {
        produced[j] = strokes[j];
    }
    for (a = 0; a < t->n; ++a) {
        if (t->force[a] >= 0) {
            const double *c = pr + 6 * t->point[a] + 2, *p0 = rest + 2 * a;
            produced[t->stroke[a]] = t->direction[2 * a] * (c[0] - p0[0])
                                     + t->direction[2 * a + 1] * (c[1] - p0[1]);
        }
    }
    s = sk_stroke_solve(m, t, xr, params, SK_LEVEL_RIGID, 0, 0, rest, produced,
                        sk_stroke_tol(t, rest), jac, &at);
    ref = at.out; /* the rigid linkage at xr: the solve's last evaluation */
    for (j = 0; j < SK_M && s == 0; ++j) {
        ar[j] = at.angles[j];
    }
    if (s != 0) {
        /* beyond the rigid reach: no reference (ar keeps the first solve's angles) */
        for (i = 0; i < 6 * SK_NP; ++i) {
            ref[i] = NAN;
        }
        s = 4;
    }
    for (i = 0; i < SK_NP; ++i) {
        for (j = 0; j < 2; ++j) {
            pr[6 * i + j] = ref[6 * i + j];
            pr[6 * i + 4 + j] = pr[6 * i + 2 + j] - ref[6 * i + j];
        }
    }
    return s;
}

#endif
/* The loaded level with actuators, laid out as sk_actuated_kinematic's: the reduced equilibrium
   at the rigid linkage at the strokes, the surrogates free (docs/physics.md, "Actuators at
   loaded"); its deviation is the answer's, the surrogates' turn (q's x after the non-input
   hinges') in the compliant angles and the links' deviations; a force actuator's deviations
   against the rigid linkage at the stroke it produced; the solution in sol. Returns 0, or a
   status code. */
static int sk_actuated_loaded(const sk_mechanism *m, const sk_actuators *t, const double *drives,
                              const double *params, double *pr, double *ar, double *lr,
                              sk_act_solution *sol)
{
    const sk_level *lv = sk_find_level(m, SK_LEVEL_LOADED);
    const sk_loaded *l = (const sk_loaded *)m->loaded;
    double rest[2 * SK_NI], xr[SK_NI + 1], delta[SK_K + 1], turned[SK_M];
    double *theta = sol->theta;
    sk_stroke_jac jac;
    sk_stroke_at er;
#if defined(SK_ACT_FORCES)
    double strokes[SK_NI + 1];
#else
    const double *strokes = drives;
#endif
    const double *q = NULL;
    int i, j, v, s;
    if (params == NULL) {
        params = m->defaults;
    }
    s = 0;
#if defined(SK_ACT_FORCES)
    s = sk_force_split(t, drives, strokes, theta);
#endif
    s = s != 0 ? s : sk_stroke_rigid(m, t, strokes, params, SK_LEVEL_RIGID, xr, rest, &jac, &er);
    s = s != 0 ? s : sk_pose(m, lv, xr, params, lr != NULL, theta, delta, sol->constants, &q);
    s = s != 0 ? s : sk_outputs(m, lv, theta, delta, params, q, pr, ar, lr);
    sol->q = q;
    if (s != 0) {
        return s;
    }
    v = (int)q[SK_NPAR + 2 * SK_NP];
    for (j = 0; j < SK_M; ++j) {
        turned[j] = theta[j];
    }
    for (i = 0; i < t->n; ++i) {
        const int h = l->unknown_index[SK_K + i];
        const double d = q[SK_NPAR + 2 * SK_NP + 1 + SK_K + i] * l->variants[v].scale[SK_K + i];
        ar[SK_M + h] += d;
        turned[h] += d;
    }
#if defined(SK_ACT_FORCES)
    s = sk_force_reference(m, t, strokes, params, rest, &jac, xr, pr, ar);
#endif
#if defined(SK_LINKS)
    if ((s == 0 || s == 4) && lr != NULL) {
        /* each link's rotation at the surrogates' compliant angles less the reference's (the
           rigid angles, ar), plus the non-input hinges' deviation; beyond the rigid reach (4)
           against the first solve's, the rigid rotation and the deviation NaN */
        double rot[2 * SK_NL + 1], rot0[2 * SK_NL + 1];
        m->links(turned, delta, rot);
        m->links(ar, delta, rot0);
        for (j = 0; j < SK_NL; ++j) {
            const double dev = rot[j] - rot0[j] + rot[SK_NL + j];
            lr[3 * j] = sk_wrap(rot0[j]);
            lr[3 * j + 1] = lr[3 * j] + dev;
            lr[3 * j + 2] = s == 4 ? NAN : dev;
            lr[3 * j] = s == 4 ? NAN : lr[3 * j];
        }
    }
#endif
    for (j = 0; s == 4 && j < SK_M; ++j) {
        ar[j] = NAN;
    }
    return s;
}

#endif
/* <name>_evaluate_pose with actuators: the public inputs (input hinges, then strokes or forces),
   the reported points only (sk_actuated_kinematic, sk_actuated_loaded). */
static int sk_actuated_pose(const sk_mechanism *m, const sk_actuators *t, const double *drives,
                            const double *params, int level, double *out, double *angles,
                            double *links)
{
    double pr[6 * SK_NP], ar[2 * SK_M], lr[3 * SK_NL + 1];
    int i, j, s;
    if (drives == NULL || out == NULL) {
        return 3;
    }
#if defined(SK_ACT_LOADED)
    if (level == SK_LEVEL_LOADED) {
        sk_act_solution sol;
        s = sk_actuated_loaded(m, t, drives, params, pr, ar, links == NULL ? NULL : lr, &sol);
    } else
#endif
    {
        s = sk_actuated_kinematic(m, t, drives, params, level, pr, ar, links == NULL ? NULL : lr);
    }
    if (s != 0 && s != 4) {
        sk_nan(out, 6 * t->n_shown);
        sk_nan(angles, 2 * SK_M);
        sk_nan(links, 3 * SK_NL);
        return s;
    }
    for (i = 0; i < t->n_shown; ++i) {
        for (j = 0; j < 6; ++j) {
            out[6 * i + j] = pr[6 * t->shown[i] + j];
        }
    }
    for (j = 0; angles != NULL && j < 2 * SK_M; ++j) {
        angles[j] = ar[j];
    }
    for (j = 0; links != NULL && j < 3 * SK_NL; ++j) {
        links[j] = lr[j];
    }
    return s; /* 0, or 4: beyond the rigid reach, the rigid values and deviations NaN */
}

/* <name>_evaluate_angles_batch with actuators: n rows; the number of rows that failed (a row
   beyond the rigid reach, status 4, is not a failure). */
static int sk_actuated_rows(const sk_mechanism *m, const sk_actuators *t, int n,
                            const double *drives, const double *params, int level, double *out,
                            double *angles, int *status)
{
    int j, s, failed = 0;
    for (j = 0; j < n; ++j) {
        s = drives == NULL ? 3 : sk_actuated_pose(
            m, t, drives + (size_t)j * SK_NI, params, level,
            out == NULL ? NULL : out + (size_t)j * 6 * t->n_shown,
            angles == NULL ? NULL : angles + (size_t)j * 2 * SK_M, NULL);
        failed += s != 0 && s != 4;
        if (status != NULL) {
            status[j] = s;
        }
    }
    return failed;
}

/* <name>_evaluate_grid with actuators: every parameter set at every row; the number failed. */
static int sk_actuated_grid(const sk_mechanism *m, const sk_actuators *t, int n_sets,
                            const double *params, int n, const double *drives, int level,
                            double *out, int *status)
{
    int s, failed = 0;
    (void)sk_evaluate_grid; /* the runtime's, for input angles: the public one is this */
    for (s = 0; s < n_sets; ++s) {
        failed += sk_actuated_rows(
            m, t, n, drives, params == NULL ? NULL : params + (size_t)s * SK_NPAR, level,
            out == NULL ? NULL : out + (size_t)s * n * 6 * t->n_shown, NULL,
            status == NULL ? NULL : status + (size_t)s * n);
    }
    return failed;
}
#if defined(SK_ACT_REPORT)

/* <name>_loaded_report with actuators (the generated header documents it): the configuration
   solved as <name>_evaluate's at loaded (sk_actuated_loaded), then sk_reduced_report at its
   solution with the actuators' rows read as inputs after the input hinges', unscaled (as numpy's
   _actuated_report; symkin.codegen.loaded's loaded_report<g>): the input hinges' moments and
   dM/dtheta in N m, the points' stiffness and the plates' stress as without actuators, then
   per actuator its stroke, force and dF/ds (a stroke's force and dF/ds; a force's stroke and
   1/(ds/dF), inf where ds/dF = 0), then the points' compliance. out NaN on any non-zero
   return. */
static int sk_actuated_report(const sk_mechanism *m, const sk_actuators *t,
                              const sk_loaded_report *rp, const double *drives,
                              const double *params, double *out)
{
    /* sk_reduced_report's answer with the actuators' rows: 2 per row (input hinges, then
       actuators), 9 per point, 4 per plate (fewer plates than SK_RS), 9 per point */
    double raw[6 * SK_RQ + 4 * SK_RS], pr[6 * SK_NP], ar[2 * SK_M], *acts;
    const int nin = rp->n_inputs, rows = nin + t->n;
    const int size = 2 * nin + 9 * rp->n_points + 4 * rp->n_plates + 3 * t->n + 9 * rp->n_points;
    sk_loaded_report with = *rp;
    sk_act_solution sol;
    int i, a, s;
    (void)sk_loaded_report_pose; /* the runtime's, for input angles: the public one is this */
    if (out == NULL) {
        return 3;
    }
    acts = out + 2 * nin + 9 * rp->n_points + 4 * rp->n_plates;
    with.n_inputs = rows;
    with.unit_scale = 1.0;
    s = drives == NULL ? 3 : sk_actuated_loaded(m, t, drives, params, pr, ar, NULL, &sol);
    s = s == 4 ? 0 : s; /* beyond the rigid reach: the report is the compliant pose's */
    s = s != 0 ? s : sk_reduced_report(m, &with, sol.theta, sol.q, raw);
    for (i = 0; s == 0 && i < 2 * rows; ++i) {
        if (!isfinite(raw[i])) {
            s = 2;                  /* a non-finite moment, force or stroke is never a success */
        }
    }
    if (s != 0) {
        sk_nan(out, size);
        return s;
    }
    for (i = 0; i < 2 * nin; ++i) {
        out[i] = raw[i] * rp->unit_scale;
    }
    for (i = 0; i < 9 * rp->n_points + 4 * rp->n_plates; ++i) {
        out[2 * nin + i] = raw[2 * rows + i];
    }
    for (i = 0; i < 9 * rp->n_points; ++i) {
        /* the compliance block, after the actuators' */
        acts[3 * t->n + i] = raw[2 * rows + 9 * rp->n_points + 4 * rp->n_plates + i];
    }
    for (a = 0; a < t->n; ++a) {
        const double value = raw[2 * (nin + a)], rate = raw[2 * (nin + a) + 1];
        const double given = drives[t->stroke[a]];
#if defined(SK_ACT_FORCES)
        if (t->force[a] >= 0) {
            acts[3 * a] = value;
            acts[3 * a + 1] = given;
            acts[3 * a + 2] = rate != 0.0 ? 1.0 / rate : HUGE_VAL;
            continue;
        }
#endif
        acts[3 * a] = given;
        acts[3 * a + 1] = value;
        acts[3 * a + 2] = rate;
#if defined(SK_ACT_SPRINGS)
        if (t->spring[a]) {
            /* the actual stroke: the command plus its point's deviation along d from the rigid
               linkage at the command (d.dX = -force/spring) */
            const double *dev = pr + 6 * t->point[a] + 4;
            acts[3 * a] = given + t->direction[2 * a] * dev[0] + t->direction[2 * a + 1] * dev[1];
        }
#endif
    }
    return 0;
}
#endif
#if defined(SK_SENSITIVITY)

/* The surrogates' rates dv/dy (t->n x SK_NV, row-major) at one pose, from that pose's
   sk_sensitivity_full (dev NULL: the rigid linkage, else the compliant mechanism, whose point
   of action is rigid + deviation) and the points' rigid rates as fabricated (rest): the
   implicit-function theorem on g(v, y) = d.(X(v, y) - X0(y)) - s = 0, dv/dy = -(dg/dv)^-1 dg/dy,
   y the parameters, then the public inputs (input hinges, strokes). Returns 0 or 1 (singular). */
static int sk_stroke_rates(const sk_actuators *t, const int *where, const double *rig,
                           const double *dev, const double *rest, double *rate)
{
    double jac[(SK_NI + 1) * (SK_NI + 1)];
    int a, b, j, y, n = t->n;
    for (a = 0; a < n; ++a) {
        const double *d = t->direction + 2 * a;
        const size_t at = (size_t)t->point[a] * SK_NV;
        for (b = 0; b < n; ++b) {
            const size_t v = (at + SK_NPAR + where[b]) * 2;
            jac[a * n + b] = d[0] * (rig[v] + (dev ? dev[v] : 0.0))
                             + d[1] * (rig[v + 1] + (dev ? dev[v + 1] : 0.0));
        }
        for (y = 0; y < SK_NV; ++y) {
            double g = 0.0;
            int k = y - SK_NPAR;
            if (k < 0 || t->drive_of[k] >= 0) {
                /* a parameter or input hinge k: its kinematic input is the one it drives */
                int x = y;
                if (k >= 0) {
                    for (j = 0; j < SK_NI; ++j) {
                        x = t->drive_of[j] == k ? SK_NPAR + j : x;
                    }
                }
                g = d[0] * (rig[(at + x) * 2] + (dev ? dev[(at + x) * 2] : 0.0))
                    + d[1] * (rig[(at + x) * 2 + 1] + (dev ? dev[(at + x) * 2 + 1] : 0.0));
                if (k < 0) { /* the point of action as fabricated moves with the parameters */
                    g -= d[0] * rest[(at + y) * 2] + d[1] * rest[(at + y) * 2 + 1];
                }
            }
            rate[a * SK_NV + y] = -g;
        }
    }
    for (a = 0; a < n; ++a) { /* the strokes: dg_a/ds_b = -1 for a = b */
        rate[a * SK_NV + SK_NPAR + t->stroke[a]] = 1.0;
    }
    return sk_act_solve(n, jac, SK_NV, rate);
}

#if defined(SK_ACT_SENS)
/* sk_actuated_sensitivity at the loaded level (stroke actuators): the reduced equilibrium's
   rates at the solution sk_actuated_loaded found (sk_sensitivity: the surrogate angles among
   the inputs), carried to the public inputs through each surrogate angle of the rigid linkage
   at the strokes, d.(X(v, y) - X0(y)) - s = 0 (sk_stroke_rates on the rigid rates): dD/dy + dD/dv
   dv/dy for the deviation and the rigid position alike (numpy's
   _actuated_loaded_sensitivity). Returns 0, or the status of what failed. */
static int sk_actuated_loaded_rates(const sk_mechanism *m, const sk_actuators *t,
                                    const double *drives, const double *params, const int *where,
                                    const int *direct, double *values, double *deviation,
                                    double *rigid)
{
    enum { NS = 2 * SK_NP * SK_NV + 1 };
    double pr[6 * SK_NP], ar[2 * SK_M], zero[SK_M];
    double dev[NS], rig[NS], r0[NS], scratch[NS], th[SK_K * SK_NV + 1];
    double pub[3][NS], rate[(SK_NI + 1) * SK_NV];
    double *tables[3] = {dev, rig, r0};
    sk_act_solution sol;
    int i, j, c, y, s;
    if (params == NULL) {
        params = m->defaults;
    }
    for (j = 0; j < SK_M; ++j) {
        zero[j] = 0.0;
    }
    for (i = 0; i < NS; ++i) {
        scratch[i] = 0.0;
    }
    s = sk_actuated_loaded(m, t, drives, params, pr, ar, NULL, &sol);
    s = s != 0 ? s
               : sk_sensitivity(m, sk_find_level(m, SK_LEVEL_LOADED), sol.theta, NULL, params,
                                sol.q, dev, rig);
    /* the points of action as fabricated (every hinge angle 0) move with the parameters too */
    s = s != 0 ? s : sk_rigid_rates(m, zero, params, th, r0);
    s = s != 0 ? s : sk_sensitivity_chain(m, params, scratch, r0);
    if (s != 0) {
        return s;
    }
    /* in <name>_sensitivity_full's layout, (point, variable, component), as sk_stroke_rates
       reads them (these are (2 point + component, variable)) */
    for (j = 0; j < 3; ++j) {
        for (i = 0; i < 2 * SK_NP * SK_NV; ++i) {
            pub[j][((i / SK_NV / 2) * SK_NV + i % SK_NV) * 2 + (i / SK_NV) % 2] = tables[j][i];
        }
    }
    s = sk_stroke_rates(t, where, pub[1], NULL, pub[2], rate);
    if (s != 0) {
        return s;
    }
    for (i = 0; i < t->n_shown; ++i) {
        const size_t at = (size_t)t->shown[i] * SK_NV;
        for (c = 0; c < 6 && values != NULL; ++c) {
            values[6 * i + c] = pr[6 * t->shown[i] + c];
        }
        for (c = 0; c < 2; ++c) {
            for (y = 0; y < SK_NV; ++y) {
                double r = 0.0, k = 0.0;
                if (direct[y] >= 0) {
                    r = pub[1][(at + direct[y]) * 2 + c];
                    k = pub[0][(at + direct[y]) * 2 + c];
                }
                for (j = 0; j < t->n; ++j) {
                    const size_t v = (at + SK_NPAR + where[j]) * 2 + c;
                    r += pub[1][v] * rate[j * SK_NV + y];
                    k += pub[0][v] * rate[j * SK_NV + y];
                }
                if (!isfinite(r) || !isfinite(k)) {
                    return 2; /* a non-finite result is never a success */
                }
                deviation[(i * SK_NV + y) * 2 + c] = k;
                if (rigid != NULL) {
                    rigid[(i * SK_NV + y) * 2 + c] = r;
                }
            }
        }
    }
    return 0;
}

#endif
/* <name>_sensitivity_full with actuators: the shown points' values and the derivatives of their
   deviation and rigid position by the parameters and the public inputs (docs/sensitivity.md,
   "Actuators"), from sk_sensitivity_full at the rigid and the compliant pose; at loaded,
   sk_actuated_loaded_rates. */
static int sk_actuated_sensitivity(const sk_mechanism *m, const sk_actuators *t,
                                   const double *drives, const double *params, int level,
                                   double *values, double *deviation, double *rigid)
{
    enum { NS = 2 * SK_NP * SK_NV + 1 };
    double rest[2 * SK_NI], xr[SK_NI + 1], xc[SK_NI + 1], zero[SK_NI + 1];
    double pr[6 * SK_NP], pc[6 * SK_NP], dr[NS], rr[NS], dc[NS], rc[NS], r0[NS], d0[NS];
    double rate_r[(SK_NI + 1) * SK_NV], rate_c[(SK_NI + 1) * SK_NV];
    int where[SK_NI + 1], direct[SK_NV];
    sk_stroke_at er, ec;
    int i, j, c, y, s;
    if (drives == NULL || deviation == NULL) {
        return 3;
    }
#if defined(SK_ACT_FORCES)
    if (level == SK_LEVEL_LOADED) {
        /* no sensitivities at loaded with force actuators yet (the stroke solves below would
           read a force as a stroke), and the file has no other level */
        sk_nan(values, 6 * t->n_shown);
        sk_nan(deviation, 2 * t->n_shown * SK_NV);
        sk_nan(rigid, 2 * t->n_shown * SK_NV);
        return 3;
    }
#endif
    for (j = 0; j < SK_NI; ++j) {
        zero[j] = 0.0;
        if (t->drive_of[j] < 0) {
            where[-1 - t->drive_of[j]] = j;
        }
    }
    /* the kinematic variable each public one moves directly (-1: a stroke moves none) */
    for (y = 0; y < SK_NV; ++y) {
        direct[y] = y < SK_NPAR ? y : -1;
    }
    for (j = 0; j < SK_NI; ++j) {
        if (t->drive_of[j] >= 0) {
            direct[SK_NPAR + t->drive_of[j]] = SK_NPAR + j;
        }
    }
#if defined(SK_ACT_SENS)
    if (level == SK_LEVEL_LOADED) {
        s = sk_actuated_loaded_rates(m, t, drives, params, where, direct, values, deviation,
                                     rigid);
        if (s != 0) {
            sk_nan(values, 6 * t->n_shown);
            sk_nan(deviation, 2 * t->n_shown * SK_NV);
            sk_nan(rigid, 2 * t->n_shown * SK_NV);
        }
        return s;
    }
#endif
    s = sk_stroke_poses(m, t, drives, params, level, xr, xc, rest, &er, &ec, 0);
    s = s != 0 ? s : sk_sensitivity_full(m, xr, params, level, pr, dr, rr);
    s = s != 0 ? s : sk_sensitivity_full(m, xc, params, level, pc, dc, rc);
    s = s != 0 ? s : sk_sensitivity_full(m, zero, params, level, NULL, d0, r0);
    s = s != 0 ? s : sk_stroke_rates(t, where, rr, NULL, r0, rate_r);
    s = s != 0 ? s : sk_stroke_rates(t, where, rc, dc, r0, rate_c);
    if (s != 0) {
        sk_nan(values, 6 * t->n_shown);
        sk_nan(deviation, 2 * t->n_shown * SK_NV);
        sk_nan(rigid, 2 * t->n_shown * SK_NV);
        return s;
    }
    for (i = 0; i < t->n_shown; ++i) {
        const size_t at = (size_t)t->shown[i] * SK_NV;
        for (c = 0; c < 2; ++c) {
            if (values != NULL) {
                values[6 * i + c] = pr[6 * t->shown[i] + c];
                values[6 * i + 2 + c] = pc[6 * t->shown[i] + 2 + c];
                values[6 * i + 4 + c] = pc[6 * t->shown[i] + c] - pr[6 * t->shown[i] + c]
                                        + pc[6 * t->shown[i] + 4 + c];
            }
            for (y = 0; y < SK_NV; ++y) {
                double r = 0.0, k = 0.0;
                if (direct[y] >= 0) {
                    r = rr[(at + direct[y]) * 2 + c];
                    k = rc[(at + direct[y]) * 2 + c] + dc[(at + direct[y]) * 2 + c];
                }
                for (j = 0; j < t->n; ++j) {
                    const size_t v = (at + SK_NPAR + where[j]) * 2 + c;
                    r += rr[v] * rate_r[j * SK_NV + y];
                    k += (rc[v] + dc[v]) * rate_c[j * SK_NV + y];
                }
                deviation[(i * SK_NV + y) * 2 + c] = k - r;
                if (rigid != NULL) {
                    rigid[(i * SK_NV + y) * 2 + c] = r;
                }
            }
        }
    }
    return 0;
}

/* <name>_sensitivity with actuators: the parameters' columns of the deviation's derivatives. */
static int sk_actuated_sensitivity_params(const sk_mechanism *m, const sk_actuators *t,
                                          const double *drives, const double *params, int level,
                                          double *out)
{
    double full[2 * SK_NP * SK_NV + 1];
    int p, v, status;
    if (out == NULL) {
        return 3;
    }
    status = sk_actuated_sensitivity(m, t, drives, params, level, NULL, full, NULL);
    for (p = 0; p < t->n_shown; ++p) {
        for (v = 0; v < SK_NPAR; ++v) {
            out[(p * SK_NPAR + v) * 2] = full[(p * SK_NV + v) * 2];
            out[(p * SK_NPAR + v) * 2 + 1] = full[(p * SK_NV + v) * 2 + 1];
        }
    }
    return status;
}

/* <name>_sensitivity_batch with actuators: n rows; the number of rows that failed. */
static int sk_actuated_sensitivity_rows(const sk_mechanism *m, const sk_actuators *t, int n,
                                        const double *drives, const double *params, int level,
                                        double *values, double *deviation, double *rigid,
                                        int *status)
{
    int j, s, failed = 0;
    (void)sk_sensitivity_rows; /* the runtime's, for input angles: the public one is this */
    (void)sk_sensitivity_params;
    for (j = 0; j < n; ++j) {
        s = drives == NULL || deviation == NULL ? 3 : sk_actuated_sensitivity(
            m, t, drives + (size_t)j * SK_NI, params, level,
            values == NULL ? NULL : values + (size_t)j * 6 * t->n_shown,
            deviation + (size_t)j * 2 * t->n_shown * SK_NV,
            rigid == NULL ? NULL : rigid + (size_t)j * 2 * t->n_shown * SK_NV);
        failed += s != 0;
        if (status != NULL) {
            status[j] = s;
        }
    }
    return failed;
}
#endif
