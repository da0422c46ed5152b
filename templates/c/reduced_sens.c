/*
 * symkin's C runtime for the `loaded` level's sensitivities (docs/sensitivity.md;
 * symkin.physics.reduced_sensitivity): the implicit-function theorem on the reduced equilibrium
 * R(x, theta, p) = 0 at the solution templates/c/reduced.c found, over the mechanism's
 * loaded_sens<g> and plate_eps4 routines. Only evaluators with the level and sensitivities hold
 * it (templates/c/source.c.j2), after templates/c/reduced.c, whose sk_red_at_solution it calls.
 */
#include <math.h>
#include <stddef.h>

/* ---- symkin runtime: every generated .c with the loaded level's sensitivities holds it ---- */

/* One variant's sensitivity routine (x, theta, plates, params) and where its blocks start:
   dR/dtheta (n x m), dR/dp (n x n_p), din/dtheta (5 n_s x m), din/dp (5 n_s x n_p), dD/dx
   (2 n_P x n), dD/dtheta (2 n_P x m), dD/dp (2 n_P x n_p), dD/dout (2 n_P x 3 n_s). */
typedef struct {
    sk_fn4 fn;
    int dR_dtheta, dR_dp, din_dtheta, din_dp, dD_dx, dD_dtheta, dD_dp, dD_dout;
} sk_red_sens;

/* The loaded level's sensitivity routines, one per variant of sk_loaded. */
typedef struct {
    sk_red_sens variants[2];
} sk_loaded_sens;

/* dev (2 SK_NP x SK_NV) of the loaded level at its solution: q holds the parameters, the
   deviation, the variant solved and its x (sk_reduced_pose); thu dtheta_u/dv of the non-input
   hinges (SK_K x SK_NV, NULL without). J is evaluated once more at the solution (its LU, the
   plates' inputs and relation there: everything the chain rule reads), then
   dx/dv = -J^-1 (dR/dtheta dtheta/dv + dR/dp + dR/dout dout/din din/dv) and
   dD/dv = dD/dx dx/dv + dD/dtheta dtheta/dv + dD/dp + dD/dout dout/din (din/dv + din/dx dx/dv).
   Returns 0, or 1 where J is singular. */
static int sk_reduced_rates(const void *mechanism, const double *theta, const double *q,
                            const double *thu, double *dev)
{
    const sk_mechanism *m = (const sk_mechanism *)mechanism;
    const int v = (int)q[SK_NPAR + 2 * SK_NP];
    const sk_red_sens *rs = ((const sk_loaded_sens *)m->loaded_sens)->variants + v;
    double s[SK_OUT], vals[3 * SK_RS], eps[6];
    double dth[SK_M * SK_NV + 1], din[5 * SK_RS * SK_NV + 1], dout[3 * SK_RS * SK_NV + 1];
    double dx[SK_RN * SK_NV + 1], col[SK_RN + 1], part[3 * SK_RS * 5 + 1];
    sk_red_state st;
    sk_red r;
    int n, ns, i, j, k, c, e;
    if (sk_red_at_solution(m, theta, q, &r, &st, vals)) {
        return 1;
    }
    n = r.v->size;
    ns = r.v->plates_n;
    rs->fn(st.xt, theta, vals, q, s);
    /* dtheta/dv of every hinge: the non-input ones' from the rigid closure, an input's own 1 */
    for (i = 0; i < SK_M * SK_NV; ++i) {
        dth[i] = 0.0;
    }
    for (j = 0; j < SK_K && thu != NULL; ++j) {
        for (c = 0; c < SK_NV; ++c) {
            dth[m->unknown_index[j] * SK_NV + c] = thu[j * SK_NV + c];
        }
    }
    for (i = 0; i < SK_NI; ++i) {
        dth[m->input_index[i] * SK_NV + SK_NPAR + i] = 1.0;
    }
    /* the relation's partials by (theta_c, p, f, e_a, e_s), 3 x 5 per half plate */
    for (k = 0; k < ns; ++k) {
        sk_plate_eps4(st.ins + 5 * k, eps);
        for (i = 0; i < 3; ++i) {
            for (c = 0; c < 3; ++c) {
                part[15 * k + 5 * i + c] = st.rel[12 * k + 3 + 3 * i + c];
            }
            part[15 * k + 5 * i + 3] = eps[2 * i];
            part[15 * k + 5 * i + 4] = eps[2 * i + 1];
        }
    }
    /* din/dv at fixed x, then dout/dv = dout/din din/dv */
    for (i = 0; i < 5 * ns; ++i) {
        for (c = 0; c < SK_NV; ++c) {
            double sum = c < SK_NPAR ? s[rs->din_dp + i * SK_NPAR + c] : 0.0;
            for (e = 0; e < SK_M; ++e) {
                sum += s[rs->din_dtheta + i * SK_M + e] * dth[e * SK_NV + c];
            }
            din[i * SK_NV + c] = sum;
        }
    }
    for (k = 0; k < ns; ++k) {
        for (i = 0; i < 3; ++i) {
            for (c = 0; c < SK_NV; ++c) {
                double sum = 0.0;
                for (e = 0; e < 5; ++e) {
                    sum += part[15 * k + 5 * i + e] * din[(5 * k + e) * SK_NV + c];
                }
                dout[(3 * k + i) * SK_NV + c] = sum;
            }
        }
    }
    /* dx/dv = -J^-1 dR/dv at fixed x, column by column with J's LU */
    for (c = 0; c < SK_NV; ++c) {
        for (i = 0; i < n; ++i) {
            const double *jo = st.sys + n + n * n + i * 3 * ns;
            double sum = c < SK_NPAR ? s[rs->dR_dp + i * SK_NPAR + c] : 0.0;
            for (e = 0; e < SK_M; ++e) {
                sum += s[rs->dR_dtheta + i * SK_M + e] * dth[e * SK_NV + c];
            }
            for (e = 0; e < 3 * ns; ++e) {
                sum += jo[e] * dout[e * SK_NV + c];
            }
            col[i] = -sum;
        }
        if (n > 0) {
            sk_lu_solve(n, st.lu, st.piv, col);
        }
        for (i = 0; i < n; ++i) {
            dx[i * SK_NV + c] = col[i];
        }
    }
    /* dout/dv along the solution: + dout/din din/dx dx/dv (theta_c, p, f move with x) */
    for (k = 0; k < ns; ++k) {
        for (i = 0; i < 3; ++i) {
            for (c = 0; c < SK_NV; ++c) {
                double sum = 0.0;
                for (e = 0; e < 3; ++e) {
                    const double *dinx = st.ins + 5 * ns + (3 * k + e) * n;
                    for (j = 0; j < n; ++j) {
                        sum += part[15 * k + 5 * i + e] * dinx[j] * dx[j * SK_NV + c];
                    }
                }
                dout[(3 * k + i) * SK_NV + c] += sum;
            }
        }
    }
    for (i = 0; i < 2 * SK_NP; ++i) {
        for (c = 0; c < SK_NV; ++c) {
            double sum = c < SK_NPAR ? s[rs->dD_dp + i * SK_NPAR + c] : 0.0;
            for (e = 0; e < n; ++e) {
                sum += s[rs->dD_dx + i * n + e] * dx[e * SK_NV + c];
            }
            for (e = 0; e < SK_M; ++e) {
                sum += s[rs->dD_dtheta + i * SK_M + e] * dth[e * SK_NV + c];
            }
            for (e = 0; e < 3 * ns; ++e) {
                sum += s[rs->dD_dout + i * 3 * ns + e] * dout[e * SK_NV + c];
            }
            dev[i * SK_NV + c] = sum;
        }
    }
    return 0;
}
