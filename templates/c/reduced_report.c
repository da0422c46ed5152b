/*
 * symkin's C runtime for what the `loaded` level reports beyond the deviations (docs/physics.md,
 * "What loaded reports"; symkin.physics.reduced_reported): every input's moment and dM/dtheta
 * and every point's 3 x 3 stiffness and compliance by the implicit-function theorem on the
 * reduced equilibrium at the solution templates/c/reduced.c found (the mechanism's
 * loaded_report<g> routines), every plate's largest normal stress by integrating the plate from
 * its end loads with RK4, as templates/numpy/reduced_report.py. Only evaluators with the level's
 * loaded_report<g> routines hold it (templates/c/source.c.j2), after templates/c/reduced.c,
 * whose sk_red_at_solution it calls, and runtime.c's sk_pose; the generated file defines SK_RQ
 * (the inputs and three per point: the report's variables, and one).
 */
#include <math.h>
#include <stddef.h>

/* ---- symkin runtime: every generated .c with the loaded level's report holds what follows ---- */

/* One variant's report routine (x, theta, plates, params) and where its blocks start, with q
   the report's variables (the inputs' compliant angles, a virtual load (Fx, Fy, M) at every
   point) and k its quantities (the inputs' moments, every point's dx, dy, dphi; as many):
   dR/dv (n x q), din/dv (3 n_s x q), y (k), dy/dx (k x n), dy/dv (k x q), dy/dout (k x 3 n_s),
   then per plate (k0, lx, ly, e_a, e_s, t/l, E', allowable stress). */
typedef struct {
    sk_fn4 fn;
    int dR_dv, din_dv, y, dy_dx, dy_dv, dy_dout, stress;
} sk_red_rep;

/* What the report is of: per variant its routine; the inputs, points (on the frame or not),
   plates (with an allowable stress or not); metres per file unit; the scales L, F C's
   conditioning is judged by. */
typedef struct {
    sk_red_rep variants[2];
    int n_inputs, n_points, n_plates;
    const int *frame, *limits;
    double unit_scale, L, F;
} sk_loaded_report;

/* SK_LOADED_SECTIONS: sections per plate where the stress is sampled, one RK4 step each;
   SK_LOADED_SINGULAR: a point's compliance this ill-conditioned (1-norm, scaled) is singular
   (the generated file's, symkin.core.settings.LoadedSettings). */

/* The end load's components along and across the plate (fn, fq = f_N, f_Q of the plate's IVP,
   symkin.physics.beams: lx cos psi + ly sin psi, ly cos psi - lx sin psi) once it turns on by
   d, by the angle-sum rule: cos d and sin d by their Taylor series where |d| <= 0.03 (the terms
   left out below 2e-18 of them; an RK4 stage turns psi by h times its rate), libm's otherwise.
   As templates/numpy/reduced_report.py's _turn. */
static inline void sk_rep_turn(double *fn, double *fq, double d)
{
    double cd, sd;
    const double n0 = *fn, q0 = *fq;
    if (fabs(d) <= 0.03) {
        const double d2 = d * d, d4 = d2 * d2;
        cd = (1 - d2 * (1.0 / 2)) + d4 * ((1.0 / 24 - d2 * (1.0 / 720)) + d4 * (1.0 / 40320));
        sd = d * ((1 - d2 * (1.0 / 6)) + d4 * (1.0 / 120 - d2 * (1.0 / 5040)));
    } else {
        cd = cos(d);
        sd = sin(d);
    }
    *fn = n0 * cd + q0 * sd;
    *fq = q0 * cd - n0 * sd;
}

/* psi'' of the plate's IVP (symkin.physics.beams) at psi + turn: -f_Q (1 + (e_a - e_s) f_N). */
static inline double sk_rep_bend(double fn, double fq, double turn, double d)
{
    sk_rep_turn(&fn, &fq, turn);
    return -fq * (1.0 + d * fn);
}

/* Plates integrated side by side (their steps interleaved: independent chains of dependent
   operations), each with its own arithmetic, as alone. */
#define SK_REP_LANES 4

/* The plates' largest normal stress, its strain, safety factor (NaN without an allowable
   stress) and where along the plate (0..1) into out[4 k .. 4 k + 3], from rows[8 k ..] = (k0,
   lx, ly, e_a, e_s, t/l, E', allowable) of each of the n plates: psi(0) = 0, psi'(0) = k0 by
   fixed-step RK4, the load's components carried from stage to stage by the angle-sum rule
   (sk_rep_turn: no libm call where the turns are small), the strain |psi'| t/(2l) +
   |f_N| (t/l)^2/12 at every section, the parabola's vertex through the three samples around an
   interior maximum (symkin.physics.reported.plate_stress). */
static void sk_rep_plates(const double *rows, const int *limits, int n, double *out)
{
    const double h = 1.0 / SK_LOADED_SECTIONS;
    double strain[SK_REP_LANES][SK_LOADED_SECTIONS + 1];
    double fn[SK_REP_LANES], fq[SK_REP_LANES], om[SK_REP_LANES], d[SK_REP_LANES];
    double t[SK_REP_LANES];
    int first, lanes, l, i, j[SK_REP_LANES];
    for (first = 0; first < n; first += SK_REP_LANES) {
        lanes = n - first < SK_REP_LANES ? n - first : SK_REP_LANES;
        for (l = 0; l < SK_REP_LANES; ++l) {
            /* a lane past the last plate integrates zeros, unread */
            const double *row = rows + 8 * (first + (l < lanes ? l : 0));
            om[l] = l < lanes ? row[0] : 0.0;
            fn[l] = l < lanes ? row[1] : 0.0;
            fq[l] = l < lanes ? row[2] : 0.0;
            d[l] = l < lanes ? row[3] - row[4] : 0.0;
            t[l] = l < lanes ? row[5] : 0.0;
            j[l] = 0;
        }
        for (i = 0; i <= SK_LOADED_SECTIONS; ++i) {
            for (l = 0; l < SK_REP_LANES; ++l) {
                strain[l][i] = fabs(om[l]) * t[l] / 2.0 + fabs(fn[l]) * t[l] * t[l] / 12.0;
                if (strain[l][i] > strain[l][j[l]]) {
                    j[l] = i;       /* the first largest, as numpy's argmax */
                }
                if (i < SK_LOADED_SECTIONS) {
                    const double w = om[l], b1 = -fq[l] * (1.0 + d[l] * fn[l]);
                    const double b2 = sk_rep_bend(fn[l], fq[l], h / 2 * w, d[l]);
                    const double a2 = w + h / 2 * b1, a3 = w + h / 2 * b2;
                    const double b3 = sk_rep_bend(fn[l], fq[l], h / 2 * a2, d[l]);
                    const double a4 = w + h * b3, b4 = sk_rep_bend(fn[l], fq[l], h * a3, d[l]);
                    sk_rep_turn(fn + l, fq + l, h / 6 * (w + 2 * a2 + 2 * a3 + a4));
                    om[l] = w + h / 6 * (b1 + 2 * b2 + 2 * b3 + b4);
                }
            }
        }
        for (l = 0; l < lanes; ++l) {
            const double *row = rows + 8 * (first + l), *e = strain[l];
            double value = e[j[l]], where = (double)j[l] / SK_LOADED_SECTIONS, stress;
            double *o = out + 4 * (first + l);
            if (j[l] > 0 && j[l] < SK_LOADED_SECTIONS) {
                const double a = e[j[l] - 1], b = e[j[l]], c = e[j[l] + 1];
                const double bend = a - 2 * b + c;
                if (bend < 0) {
                    const double shift = (a - c) / (2 * bend);
                    value = b - (a - c) * shift / 4;
                    where = (j[l] + shift) / SK_LOADED_SECTIONS;
                }
            }
            stress = row[6] * value;
            o[0] = stress;
            o[1] = value;
            o[2] = !limits[first + l] ? NAN : stress > 0 ? row[7] / stress : HUGE_VAL;
            o[3] = where;
        }
    }
}

/* The 1-norm of a 3 x 3 matrix. */
static double sk_rep_norm1(const double *a)
{
    double best = 0.0;
    int c;
    for (c = 0; c < 3; ++c) {
        const double s = fabs(a[c]) + fabs(a[3 + c]) + fabs(a[6 + c]);
        best = s > best ? s : best;
    }
    return best;
}

/* K = C^-1 and C of a point's compliance c (3 x 3) into k and cout, NaN where either does not
   exist, as symkin.physics.reported.stiffness_and_compliance judges them: S = C scaled by L and
   F, singular where its 1-norm times its inverse's exceeds SK_LOADED_SINGULAR (or C has no
   inverse); then k NaN and cout's entries within |S|/SK_LOADED_SINGULAR of zero exactly 0 where
   |S| <= |S^-1| (a direction held rigidly), else cout NaN (a direction free); both NaN where C
   is not finite. */
static void sk_rep_stiffness(const sk_loaded_report *rp, const double *c, double *k,
                             double *cout)
{
    const double w[3] = {rp->F / rp->L, rp->F / rp->L, rp->F}, u[3] = {1.0, 1.0, 1.0 / rp->L};
    double lu[9], scaled[9], inv[9], col[3], size, inverse_size = HUGE_VAL;
    int piv[3], i, j, finite = 1, invertible;
    for (i = 0; i < 9; ++i) {
        lu[i] = c[i];
        scaled[i] = c[i] * w[i / 3] * u[i % 3];
        k[i] = cout[i] = NAN;
        finite = finite && isfinite(c[i]);
    }
    if (!finite) {
        return;
    }
    size = sk_rep_norm1(scaled);
    invertible = !sk_lu(3, lu, piv);
    for (j = 0; invertible && j < 3; ++j) {
        col[0] = col[1] = col[2] = 0.0;
        col[j] = 1.0;
        sk_lu_solve(3, lu, piv, col);
        for (i = 0; i < 3; ++i) {
            inv[3 * i + j] = col[i];
        }
    }
    if (invertible) {
        /* the scaled compliance's inverse: inv with rows over u, columns over w */
        double sinv[9];
        for (i = 0; i < 9; ++i) {
            sinv[i] = inv[i] / (u[i / 3] * w[i % 3]);
            invertible = invertible && isfinite(sinv[i]);
        }
        inverse_size = sk_rep_norm1(sinv);
    }
    if (invertible && (size * inverse_size <= SK_LOADED_SINGULAR || size > inverse_size)) {
        const int regular = size * inverse_size <= SK_LOADED_SINGULAR;
        for (i = 0; i < 9; ++i) {
            k[i] = inv[i];
            cout[i] = regular ? c[i] : NAN;
        }
        return;
    }
    for (i = 0; i < 9; ++i) {
        cout[i] = fabs(scaled[i]) <= size / SK_LOADED_SINGULAR ? 0.0 : c[i];
    }
}

/* dy/dv (ny x nv, row-major) into rates at the solution st (n unknowns, ns half plates) from a
   routine's output s whose blocks start at dR_dv (n x nv), din_dv (3 ns x nv), dy_dx (ny x n),
   dy_dv (ny x nv), dy_dout (ny x 3 ns), by the implicit-function theorem with J's LU: the
   report's rates (sk_reduced_report), the modes' compliance (templates/c/modes.c). */
static void sk_red_rates(const sk_red_state *st, int n, int ns, const double *s, int dR_dv,
                         int din_dv, int dy_dx, int dy_dv, int dy_dout, int ny, int nv,
                         double *rates)
{
    double dout[3 * SK_RS], col[SK_RN + 1];
    int i, j, k, c, e;
    for (c = 0; c < nv; ++c) {
        /* dout/dv at fixed x: the relation's partials . din/dv */
        for (k = 0; k < ns; ++k) {
            for (i = 0; i < 3; ++i) {
                double sum = 0.0;
                for (e = 0; e < 3; ++e) {
                    sum += st->rel[12 * k + 3 + 3 * i + e] * s[din_dv + (3 * k + e) * nv + c];
                }
                dout[3 * k + i] = sum;
            }
        }
        /* dx/dv = -J^-1 (dR/dv + dR/dout dout/dv) with J's LU */
        for (i = 0; i < n; ++i) {
            const double *jo = st->sys + n + n * n + i * 3 * ns;
            double sum = s[dR_dv + i * nv + c];
            for (e = 0; e < 3 * ns; ++e) {
                sum += jo[e] * dout[e];
            }
            col[i] = -sum;
        }
        if (n > 0) {
            sk_lu_solve(n, st->lu, st->piv, col);
        }
        /* dout/dv along the solution: + the partials . din/dx dx/dv */
        for (k = 0; k < ns; ++k) {
            for (i = 0; i < 3; ++i) {
                double sum = 0.0;
                for (e = 0; e < 3; ++e) {
                    const double *dinx = st->ins + 5 * ns + (3 * k + e) * n;
                    for (j = 0; j < n; ++j) {
                        sum += st->rel[12 * k + 3 + 3 * i + e] * dinx[j] * col[j];
                    }
                }
                dout[3 * k + i] += sum;
            }
        }
        for (i = 0; i < ny; ++i) {
            double sum = s[dy_dv + i * nv + c];
            for (e = 0; e < n; ++e) {
                sum += s[dy_dx + i * n + e] * col[e];
            }
            for (e = 0; e < 3 * ns; ++e) {
                sum += s[dy_dout + i * 3 * ns + e] * dout[e];
            }
            rates[i * nv + c] = sum;
        }
    }
}

/* What the loaded level reports at its solution (q: the parameters, the deviation, the variant
   solved and its x, sk_reduced_pose) into out: per input its moment (N m) and dM/dtheta
   (N m/rad), per point its stiffness K (9, row-major; NaN where it does not exist), per plate
   its stress (Pa), strain, safety factor and section, then per point its compliance C (9,
   row-major; 0 on the frame, NaN where it does not exist: sk_rep_stiffness). Returns 0, or 1
   where J is singular. */
static int sk_reduced_report(const sk_mechanism *m, const sk_loaded_report *rp,
                             const double *theta, const double *q, double *out)
{
    const sk_red_rep *rr = rp->variants + (int)q[SK_NPAR + 2 * SK_NP];
    const int nin = rp->n_inputs, nq = nin + 3 * rp->n_points;
    double s[SK_OUT], vals[3 * SK_RS];
    double rates[SK_RQ * SK_RQ];
    sk_red_state st;
    sk_red r;
    int i, k, c;
    if (sk_red_at_solution(m, theta, q, &r, &st, vals)) {
        return 1;
    }
    rr->fn(st.xt, theta, vals, q, s);
    sk_red_rates(&st, r.v->size, r.v->plates_n, s, rr->dR_dv, rr->din_dv, rr->dy_dx, rr->dy_dv,
                 rr->dy_dout, nq, nq, rates);
    for (i = 0; i < nin; ++i) {
        out[2 * i] = s[rr->y + i] * rp->unit_scale;
        out[2 * i + 1] = rates[i * nq + i] * rp->unit_scale;
    }
    out += 2 * nin;
    for (k = 0; k < rp->n_points; ++k) {
        /* the compliance block after the plates' */
        double cm[9], *cout = out + 9 * rp->n_points + 4 * rp->n_plates + 9 * k;
        for (i = 0; i < 3; ++i) {
            for (c = 0; c < 3; ++c) {
                const double v = rates[(nin + 3 * k + i) * nq + nin + 3 * k + c];
                cm[3 * i + c] = rp->frame[k] ? 0.0 : v; /* a point of the frame does not move */
            }
        }
        sk_rep_stiffness(rp, cm, out + 9 * k, cout);
    }
    out += 9 * rp->n_points;
    sk_rep_plates(s + rr->stress, rp->limits, rp->n_plates, out);
    return 0;
}

/* <name>_loaded_report (the generated header documents it): the configuration solved at the
   loaded level `level`, then sk_reduced_report; out NaN on any non-zero return. */
static int sk_loaded_report_pose(const sk_mechanism *m, const sk_loaded_report *rp, int level,
                                 const double *inputs, const double *params, double *out)
{
    double theta[SK_M], delta[SK_K + 1], constants[SK_NQ];
    const double *q;
    const sk_level *lv = sk_find_level(m, level);
    /* the inputs', the stiffness, the plates' and the compliance blocks */
    const int size = 2 * rp->n_inputs + 9 * rp->n_points + 4 * rp->n_plates + 9 * rp->n_points;
    int status, i;
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
        status = sk_reduced_report(m, rp, theta, q, out);
    }
    for (i = 0; status == 0 && i < 2 * rp->n_inputs; ++i) {
        if (!isfinite(out[i])) {
            status = 2;             /* a non-finite moment is never a success */
        }
    }
    if (status != 0) {
        sk_nan(out, size);
    }
    return status;
}
