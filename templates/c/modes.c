/*
 * symkin's C runtime for the natural frequencies and mode shapes at the `loaded` level
 * (docs/physics.md, "Natural frequencies"; docs/generated-code.md, "Natural frequencies in
 * generated code"), as templates/numpy/modes.py: the compliance of virtual loads at the massive
 * links' centres by the implicit-function theorem at the solution templates/c/reduced.c found
 * (the mechanism's loaded_modes<g> routines, assembled as reduced_report.c assembles the
 * report's), then the eigenproblem M^1/2 C M^1/2 v = v/omega^2 of symkin.physics.modes.solve by
 * cyclic Jacobi rotations on that small symmetric matrix (3 rows per massive link, a size the
 * derivation fixes: no allocation). Only evaluators whose files give links a mass hold it
 * (templates/c/source.c.j2), after templates/c/reduced_report.c; the generated file defines
 * SK_MC (3 per massive link) and SK_MR (3 per massive link and per shown point), SK_MD
 * (modes_data's outputs), SK_MODES_SWEEPS and SK_MODES_TOL
 * (symkin.core.settings.ModesSettings).
 */
#include <math.h>
#include <stddef.h>

/* ---- symkin runtime: every generated .c whose links carry mass holds what follows ---- */

/* One variant's modes routine (x, theta, plates, params) and where its blocks start, v the
   virtual loads (F_x, F_y, M) at the centres, y the centres' then the shown points' (dx, dy,
   dphi): dR/dv (n x SK_MC), din/dv (3 n_s x SK_MC), dy/dx (SK_MR x n), dy/dv (SK_MR x SK_MC),
   dy/dout (SK_MR x 3 n_s). */
typedef struct {
    sk_fn4 fn;
    int dR_dv, din_dv, dy_dx, dy_dv, dy_dout;
} sk_modes_variant;

/* What the modes are of: per variant its routine; modes_data (params -> per massive link its
   mass and inertia, then the as-fabricated (x, y) of `coordinates` points, then `lengths`
   hinge lengths); metres per file unit; the rules (symkin.core.settings.ModesSettings). */
typedef struct {
    sk_modes_variant variants[2];
    sk_fn1 data;
    int links, points, coordinates, lengths;
    double unit_scale, rigid, pure_rotation;
} sk_modes_tables;

/* The compliance cmp (SK_MR x SK_MC, row-major, file units) at the solution q of theta:
   templates/c/reduced_report.c's sk_red_rates, as sk_reduced_report's rates. Returns 0, or 1
   where J is singular. */
static int sk_modes_compliance(const sk_mechanism *m, const sk_modes_tables *mt,
                               const double *theta, const double *q, double *cmp)
{
    const sk_modes_variant *mv = mt->variants + (int)q[SK_NPAR + 2 * SK_NP];
    sk_red_state st;
    sk_red r;
    double s[SK_OUT], vals[3 * SK_RS];
    if (sk_red_at_solution(m, theta, q, &r, &st, vals)) {
        return 1;
    }
    mv->fn(st.xt, theta, vals, q, s);
    sk_red_rates(&st, r.v->size, r.v->plates_n, s, mv->dR_dv, mv->din_dv, mv->dy_dx, mv->dy_dv,
                 mv->dy_dout, SK_MR, SK_MC, cmp);
    return 0;
}

/* The eigenvalues w and eigenvectors (the columns of v, row-major) of the symmetric a (SK_MC x
   SK_MC, row-major, overwritten) by cyclic Jacobi rotations: each sweep turns every pair (p, r)
   whose off-diagonal entry is not negligible against its diagonal entries (SK_MODES_TOL times
   their geometric mean, zeroed otherwise: each eigenvalue to its own relative accuracy), until
   a sweep turns none or SK_MODES_SWEEPS sweeps. */
static void sk_modes_jacobi(double *a, double *v, double *w)
{
    const int n = SK_MC;
    int i, p, r, sweep, turned = 1;
    for (i = 0; i < n * n; ++i) {
        v[i] = i % (n + 1) == 0 ? 1.0 : 0.0;
    }
    for (sweep = 0; turned && sweep < SK_MODES_SWEEPS; ++sweep) {
        turned = 0;
        for (p = 0; p < n - 1; ++p) {
            for (r = p + 1; r < n; ++r) {
                const double apr = a[p * n + r];
                double theta, t, c, s;
                if (!(fabs(apr) > SK_MODES_TOL * sqrt(fabs(a[p * n + p] * a[r * n + r])))) {
                    a[p * n + r] = a[r * n + p] = 0.0;
                    continue;
                }
                turned = 1;
                theta = (a[r * n + r] - a[p * n + p]) / (2.0 * apr);
                t = isfinite(theta * theta) ? 1.0 / (fabs(theta) + sqrt(theta * theta + 1.0))
                                            : 0.5 / fabs(theta);
                t = theta < 0.0 ? -t : t;
                c = 1.0 / sqrt(t * t + 1.0);
                s = t * c;
                for (i = 0; i < n; ++i) {  /* a J: columns p and r */
                    const double ip = a[i * n + p], ir = a[i * n + r];
                    a[i * n + p] = c * ip - s * ir;
                    a[i * n + r] = s * ip + c * ir;
                }
                for (i = 0; i < n; ++i) {  /* J^T a J: rows p and r */
                    const double pi_ = a[p * n + i], ri = a[r * n + i];
                    a[p * n + i] = c * pi_ - s * ri;
                    a[r * n + i] = s * pi_ + c * ri;
                }
                for (i = 0; i < n; ++i) {  /* v J */
                    const double ip = v[i * n + p], ir = v[i * n + r];
                    v[i * n + p] = c * ip - s * ir;
                    v[i * n + r] = s * ip + c * ir;
                }
            }
        }
    }
    for (i = 0; i < n; ++i) {
        w[i] = a[i * n + i];
    }
}

/* The modes into out from the compliance cmp and modes_data's md (symkin.physics.modes.solve):
   SK_MC frequencies (Hz, lowest first; inf for a direction held rigidly or a degree of freedom
   without mass), then per mode its shape, per massive link (dx, dy, dphi) and per shown point
   (dx, dy), largest centre translation +1 (a pure rotation: largest rotation +1 rad; NaN for
   an infinite frequency). Returns 0, or 2 where the tangent stiffness is not positive (the
   loads beyond buckling) or a value is not finite. */
static int sk_modes_solve(const sk_modes_tables *mt, const double *cmp, const double *md,
                          double *out)
{
    const int nc = mt->links, nv = SK_MC, ny = SK_MR, size = SK_MC + 2 * mt->points;
    const double root_s = sqrt(mt->unit_scale);
    const double *at = md + 2 * nc, *lengths = at + 2 * mt->coordinates;
    double d[SK_MR], root[SK_MC], a[SK_MC * SK_MC], v[SK_MC * SK_MC], mu[SK_MC], shape[SK_MR];
    double span = 0.0, largest = 0.0, smallest = 0.0;
    int order[SK_MC], i, j, k, r;
    for (i = 0; i < ny; ++i) {
        d[i] = i % 3 == 2 ? 1.0 / root_s : root_s;  /* SI: C_SI = D C D */
    }
    for (k = 0; k < nc; ++k) {
        root[3 * k] = root[3 * k + 1] = sqrt(md[2 * k]);
        root[3 * k + 2] = sqrt(md[2 * k + 1]);  /* an inertia 0: a zero row, mu = 0 */
    }
    for (i = 0; i < mt->coordinates; ++i) {
        for (j = 0; j < mt->coordinates; ++j) {
            const double dist = hypot(at[2 * i] - at[2 * j], at[2 * i + 1] - at[2 * j + 1]);
            span = dist > span ? dist : span;
        }
    }
    for (i = 0; i < mt->lengths; ++i) {
        span = lengths[i] > span ? lengths[i] : span;
    }
    for (i = 0; i < nv; ++i) {
        for (j = 0; j < nv; ++j) {
            const double sym = (cmp[i * nv + j] + cmp[j * nv + i]) / 2.0 * d[i] * d[j];
            a[i * nv + j] = root[i] * sym * root[j];
            if (!isfinite(a[i * nv + j])) {
                return 2;
            }
        }
    }
    if (!isfinite(span)) {
        return 2;
    }
    sk_modes_jacobi(a, v, mu);
    for (i = 0; i < nv; ++i) {
        if (!isfinite(mu[i])) {
            return 2;
        }
        largest = fabs(mu[i]) > largest ? fabs(mu[i]) : largest;
        smallest = mu[i] < smallest ? mu[i] : smallest;
    }
    if (!(largest > 0.0) || smallest < -mt->rigid * largest) {
        return 2;                   /* an unstable equilibrium: no natural frequencies */
    }
    for (i = 0; i < nv; ++i) {      /* the largest mu (the lowest frequency) first */
        for (j = i; j > 0 && mu[order[j - 1]] < mu[i]; --j) {
            order[j] = order[j - 1];
        }
        order[j] = i;
    }
    for (r = 0; r < nv; ++r) {
        const int m_ = order[r];
        double *mode = out + nv + r * size, move = 0.0, turn = 0.0, scale;
        if (!(mu[m_] > mt->rigid * largest)) {
            out[r] = HUGE_VAL;      /* held rigidly: an infinite frequency */
            sk_nan(mode, size);
            continue;
        }
        out[r] = sqrt(1.0 / mu[m_]) / SK_TWO_PI;
        /* every row's response to the mode's inertia loads omega^2 M q = root v / mu */
        for (i = 0; i < ny; ++i) {
            double sum = 0.0;
            for (j = 0; j < nv; ++j) {
                sum += cmp[i * nv + j] * d[i] * d[j] * root[j] * v[j * nv + m_];
            }
            shape[i] = sum / mu[m_] / d[i];
        }
        for (k = 0; k < nc; ++k) {  /* the first largest, as numpy's argmax */
            move = fabs(shape[3 * k]) > fabs(move) ? shape[3 * k] : move;
            move = fabs(shape[3 * k + 1]) > fabs(move) ? shape[3 * k + 1] : move;
            turn = fabs(shape[3 * k + 2]) > fabs(turn) ? shape[3 * k + 2] : turn;
        }
        scale = fabs(move) <= mt->pure_rotation * fabs(turn) * span ? turn : move;
        for (k = 0; k < nc; ++k) {
            for (i = 0; i < 3; ++i) {
                mode[3 * k + i] = shape[3 * k + i] / scale;
            }
        }
        for (k = 0; k < mt->points; ++k) {
            for (i = 0; i < 2; ++i) {
                mode[nv + 2 * k + i] = shape[nv + 3 * k + i] / scale;
            }
        }
    }
    return 0;
}

/* The modes at the solution q of theta: the compliance, modes_data at q's parameters, the
   eigen-solve. Returns 0, 1 (J singular) or 2 (not stable, not finite). */
static int sk_modes_at(const sk_mechanism *m, const sk_modes_tables *mt, const double *theta,
                       const double *q, double *out)
{
    double cmp[SK_MR * SK_MC], md[SK_MD];
    if (sk_modes_compliance(m, mt, theta, q, cmp)) {
        return 1;
    }
    mt->data(q, md);
    return sk_modes_solve(mt, cmp, md, out);
}

/* <name>_modes without actuators (the generated header documents it): the configuration
   solved at the loaded level `level`, then sk_modes_at; out NaN on any non-zero return. */
static int sk_modes_pose(const sk_mechanism *m, const sk_modes_tables *mt, int level,
                         const double *inputs, const double *params, double *out)
{
    double theta[SK_M], delta[SK_K + 1], constants[SK_NQ];
    const double *q;
    const sk_level *lv = sk_find_level(m, level);
    int status;
    if (out == NULL) {
        return 3;
    }
    if (params == NULL) {
        params = m->defaults;
    }
    status = inputs == NULL || lv == NULL
                 ? 3
                 : sk_pose(m, lv, inputs, params, 0, theta, delta, constants, &q);
    if (status == 0) {
        status = sk_modes_at(m, mt, theta, q, out);
    }
    if (status != 0) {
        sk_nan(out, SK_MC * (1 + SK_MC + 2 * mt->points));
    }
    return status;
}
#if defined(SK_ACT_REPORT)

/* <name>_modes with actuators: the drives solved at loaded (templates/c/actuators.c), then
   sk_modes_at; out NaN on any non-zero return. */
static int sk_modes_actuated(const sk_mechanism *m, const sk_actuators *t,
                             const sk_modes_tables *mt, const double *drives,
                             const double *params, double *out)
{
    double pr[6 * SK_NP], ar[2 * SK_M];
    sk_act_solution sol;
    int status;
    (void)sk_modes_pose;            /* the runtime's, for input hinges: the public one is this */
    if (out == NULL) {
        return 3;
    }
    status = drives == NULL ? 3 : sk_actuated_loaded(m, t, drives, params, pr, ar, NULL, &sol);
    if (status == 0) {
        status = sk_modes_at(m, mt, sol.theta, sol.q, out);
    }
    if (status != 0) {
        sk_nan(out, SK_MC * (1 + SK_MC + 2 * mt->points));
    }
    return status;
}
#endif
