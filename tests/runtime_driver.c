/*
 * A driver of templates/c/runtime.c on its own (tests/test_runtime_c.py): it includes the runtime
 * with sizes and small routines of its own, reads commands from stdin and prints what the
 * runtime's functions return, every number with 17 significant digits.
 *
 * The toy mechanism: theta_0 the input, theta_1 and theta_2 the unknowns of a closure
 *   G(theta) = (theta_1 - p0 theta_0, theta_1 + theta_2 - theta_0),  A = dG/dtheta_u = [1 0; 1 1],
 * closed form theta_1 = p0 theta_0, theta_2 = theta_0 - theta_1 while 1 - theta_0^2 >= 0 (its
 * "reach"); a compliant closure
 *   E(delta) = (d0 + d0^3 - 0.1 theta_1, d0 + d1 - 0.05 theta_2 - c),  c = p1 (or the constants),
 * one point (cos theta_1, sin theta_2) with deviation (d0, d1) (paper: 0.1 theta_1, 0.05 theta_2),
 * one link turned by theta_1 + theta_2, and hinge 1 valid for |theta_1| <= 2.
 */
#include <stdio.h>
#include <stdlib.h>

enum { SK_M = 3, SK_K = 2, SK_NI = 1, SK_NPAR = 2, SK_NP = 1, SK_NL = 1, SK_NV = 3,
       SK_NQ = SK_NPAR + 2 + 1, SK_OUT = 32 };
/* every optional section of the runtime */
#define SK_LOOPS
#define SK_CLOSED_FORM
#define SK_CONTINUATION
#define SK_LOADED
#define SK_LINKS
#define SK_SENSITIVITY
#include "runtime.c"

/* ---- the toy mechanism's routines ---- */

static void t_rigid(const double *inputs, const double *params, double *out)
{
    out[0] = params[0] * inputs[0];
    out[1] = inputs[0] - params[0] * inputs[0];
    out[2] = 1.0 - inputs[0] * inputs[0];       /* reach */
    out[3] = 0.0;                               /* margin */
}

static void t_rigid_res(const double *theta, const double *params, double *out)
{
    out[0] = theta[1] - params[0] * theta[0];
    out[1] = theta[1] + theta[2] - theta[0];
    out[2] = 1.0;                               /* A */
    out[3] = 0.0;
    out[4] = 1.0;
    out[5] = 1.0;
}

static void t_linear(const double *theta, const double *params, double *out)
{
    out[0] = 1.0;
    out[1] = 0.0;
    out[2] = 1.0;
    out[3] = 1.0;
    out[4] = -0.1 * theta[1];
    out[5] = -0.05 * theta[2] - params[1];
    out[6] = fabs(0.1 * theta[1]);                 /* S: the size of r's terms */
    out[7] = fabs(0.05 * theta[2]) + fabs(params[1]);
}

static void t_newton(const double *theta, const double *delta, const double *params, double *out)
{
    out[0] = delta[0] + delta[0] * delta[0] * delta[0] - 0.1 * theta[1];
    out[1] = delta[0] + delta[1] - 0.05 * theta[2] - params[1];
    out[2] = 1.0 + 3.0 * delta[0] * delta[0];
    out[3] = 0.0;
    out[4] = 1.0;
    out[5] = 1.0;
}

static void t_rigid_points(const double *theta, const double *params, double *out)
{
    (void)params;
    out[0] = cos(theta[1]);
    out[1] = sin(theta[2]);
}

static void t_dev_paper(const double *theta, const double *delta, const double *params,
                        double *out)
{
    (void)delta;
    (void)params;
    out[0] = 0.1 * theta[1];
    out[1] = 0.05 * theta[2];
}

static void t_dev(const double *theta, const double *delta, const double *params, double *out)
{
    (void)theta;
    (void)params;
    out[0] = delta[0];
    out[1] = delta[1];
}

static void t_links(const double *theta, const double *delta, double *out)
{
    out[0] = theta[1] + theta[2];
    out[1] = delta[0] + delta[1];
}

/* the loaded level's driver (templates/c/reduced.c in a generated file), a stand-in:
   delta = (theta_1 / 50 + p1 / 1000, -3 theta_2 / 100), q = (p0, p1, its deviation
   (delta_0 + delta_1, 2 delta_0)); refused (status 1) when p1 theta_0 > 1 */
static int t_loaded_solve(const void *m, const double *inputs, const double *params,
                          const double *theta, double *delta, double *q)
{
    (void)m;
    (void)inputs;
    if (params[1] * theta[0] > 1.0) {
        return 1;
    }
    delta[0] = theta[1] / 50.0 + params[1] / 1000.0;
    delta[1] = -3.0 * theta[2] / 100.0;
    q[0] = params[0];
    q[1] = params[1];
    q[2] = delta[0] + delta[1];
    q[3] = 2.0 * delta[0];
    return 0;
}

static void t_loaded_dev(const double *theta, const double *delta, const double *q, double *out)
{
    (void)theta;
    (void)delta;
    out[0] = q[SK_NPAR];
    out[1] = q[SK_NPAR + 1];
}

/* sensitivities by v = (p0, p1, theta_0) */
static void t_sens_rigid(const double *theta, const double *params, double *out)
{
    static const double a[4] = {1.0, 0.0, 1.0, 1.0};
    int i;
    for (i = 0; i < 4; ++i) {
        out[i] = a[i];                              /* A */
    }
    out[4] = -theta[0];                             /* dG/dv */
    out[5] = 0.0;
    out[6] = -params[0];
    out[7] = 0.0;
    out[8] = 0.0;
    out[9] = -1.0;
    out[10] = -sin(theta[1]);                       /* dR/dtheta_u */
    out[11] = 0.0;
    out[12] = 0.0;
    out[13] = cos(theta[2]);
    for (i = 14; i < 20; ++i) {
        out[i] = 0.0;                               /* dR/dv */
    }
}

static void t_sens_paper(const double *theta, const double *delta, const double *params,
                         double *out)
{
    int i;
    (void)theta;
    (void)delta;
    (void)params;
    for (i = 0; i < 10; ++i) {
        out[i] = 0.0;
    }
    out[0] = 0.1;                                   /* dD/dtheta_u */
    out[3] = 0.05;
}

static void t_sens_exact(const double *theta, const double *delta, const double *params,
                         double *out)
{
    int i;
    (void)theta;
    (void)params;
    for (i = 0; i < 28; ++i) {
        out[i] = 0.0;
    }
    out[0] = 1.0 + 3.0 * delta[0] * delta[0];      /* M */
    out[2] = 1.0;
    out[3] = 1.0;
    out[4] = -0.1;                                  /* dE/dtheta_u */
    out[7] = -0.05;
    out[12] = -1.0;                                 /* dE/dv: dE_1/dp1 */
    out[18] = 1.0;                                  /* dD/ddelta */
    out[21] = 1.0;
}

/* p1's default is 2 p0: d(default of p1)/dp0 = 2 */
static void t_sens_chain(const double *params, double *out)
{
    (void)params;
    out[0] = 0.0;
    out[1] = 0.0;
    out[2] = 2.0;
    out[3] = 0.0;
}

static const double t_defaults[SK_NPAR] = {0.5, 1.0};
static const int t_input_index[SK_NI] = {0};
static const int t_unknown_index[SK_K] = {1, 2};
static const int t_fixed_index[1] = {0};
static const double t_fixed_angle[1] = {0.0};
static const int t_limit_index[1] = {1};
static const int t_limit_unknown[1] = {0};
static const double t_limit[1] = {2.0};
static const int t_angular[1] = {0};

static const sk_level t_levels[] = {
    {0, t_dev_paper, NULL, NULL, 0, {t_sens_paper, 0, 0, 0, 0, 0, 0, 4}, NULL, NULL},
    {1, t_dev, t_linear, NULL, 0, {NULL, 0, 0, 0, 0, 0, 0, 0}, NULL, NULL},
    {2, t_dev, t_linear, t_newton, 0, {t_sens_exact, 1, 0, 4, 8, 14, 18, 22}, NULL, NULL},
    {3, t_loaded_dev, NULL, NULL, 1, {NULL, 0, 0, 0, 0, 0, 0, 0}, NULL, NULL}
};

static sk_mechanism t_mechanism(int closed_form)
{
    sk_mechanism m = {0};
    m.defaults = t_defaults;
    m.input_index = t_input_index;
    m.unknown_index = t_unknown_index;
    m.n_fixed = 0;
    m.fixed_index = t_fixed_index;
    m.fixed_angle = t_fixed_angle;
    m.n_limits = 1;
    m.limit_index = t_limit_index;
    m.limit_unknown = t_limit_unknown;
    m.limit = t_limit;
    m.needs_loops = 1;
    m.rigid = closed_form ? t_rigid : NULL;
    m.n_dyads = 1;
    m.rigid_res = t_rigid_res;
    m.n_angular = 1;
    m.angular = t_angular;
    m.linear = t_linear;
    m.rigid_points = t_rigid_points;
    m.links = t_links;
    m.loaded_solve = t_loaded_solve;
    m.rigid_rule.iterations = 30;
    m.rigid_rule.tolerance = 1e-10;
    m.polish_rule.iterations = 1;
    m.exact_rule.iterations = 40;
    m.exact_rule.converged = 1e-8;
    m.exact_rule.stalled = 1e-12;
    m.exact_rule.stall_ratio = 0.5;
    m.exact_rule.residual = 2e-13;
    m.continuation_step = 0.05;
    m.winding = 3.141592653589793;
    m.n_levels = 4;
    m.levels = t_levels;
    m.sens_rigid = t_sens_rigid;
    m.sr_A = 0;
    m.sr_dG_dv = 4;
    m.sr_dR_dtheta = 10;
    m.sr_dR_dv = 14;
    m.sens_chain = t_sens_chain;
    return m;
}

/* ---- systems for the Newton and continuation drivers ---- */

/* f(x) = (x0^2 + x1^2 - 4, x0 - t x1), t from ctx (the continuation's stage) */
typedef struct {
    double t;
    int stages;
} t_ctx;

static void t_system(const void *ctx, const double *x, double *fj)
{
    const t_ctx *c = (const t_ctx *)ctx;
    fj[0] = x[0] * x[0] + x[1] * x[1] - 4.0;
    fj[1] = x[0] - c->t * x[1];
    fj[2] = 2.0 * x[0];
    fj[3] = 2.0 * x[1];
    fj[4] = 1.0;
    fj[5] = -c->t;
}

/* the same with the unknowns at x[3], x[1] of a longer array (sk_newton_solve's index) */
static void t_system_mapped(const void *ctx, const double *x, double *fj)
{
    double u[2];
    u[0] = x[3];
    u[1] = x[1];
    t_system(ctx, u, fj);
}

/* f(x) = x0 - (+-1e-17), the sign alternating at each evaluation: a root at zero whose
   residual never falls below rounding noise (a closure at the as-fabricated pose) */
static void t_noisy(const void *ctx, const double *x, double *fj)
{
    t_ctx *c = (t_ctx *)ctx;
    c->stages += 1;
    fj[0] = x[0] - (c->stages % 2 ? 1e-17 : -1e-17);
    fj[1] = 1.0;
}

static void t_stage(void *ctx, double t)
{
    t_ctx *c = (t_ctx *)ctx;
    c->t = t;
    c->stages += 1;
}

/* ---- the command loop ---- */

static double num(void)
{
    double x;
    if (scanf("%lf", &x) != 1) {
        fprintf(stderr, "bad input\n");
        exit(2);
    }
    return x;
}

static void read(double *x, int n)
{
    int i;
    for (i = 0; i < n; ++i) {
        x[i] = num();
    }
}

static void print(const char *label, const double *x, int n)
{
    int i;
    printf("%s", label);
    for (i = 0; i < n; ++i) {
        printf(" %.17g", x[i]);
    }
    printf("\n");
}

static void rule(sk_rule *r)
{
    r->iterations = (int)num();
    r->tolerance = num();
    r->converged = num();
    r->stalled = num();
    r->stall_ratio = num();
    r->residual = 0.0;
}

int main(void)
{
    char cmd[32];
    double a[64], b[64], x[64];
    int piv[8], n, m, status, i;
    (void)piv;
    while (scanf("%31s", cmd) == 1) {
        if (cmd[0] == 's' && cmd[1] == 'o') {            /* solve n m a b */
            n = (int)num();
            m = (int)num();
            read(a, n * n);
            read(b, n * m);
            status = sk_solve(n, a, m, b);
            printf("status %d\n", status);
            print("x", b, n * m);
        } else if (cmd[0] == 'l' && cmd[1] == 'u') {     /* lu n a b (two right-hand sides) */
            n = (int)num();
            read(a, n * n);
            read(b, 2 * n);
            status = sk_lu(n, a, piv);
            printf("status %d\n", status);
            if (status == 0) {
                sk_lu_solve(n, a, piv, b);
                sk_lu_solve(n, a, piv, b + n);
            }
            print("x", b, 2 * n);
        } else if (cmd[0] == 's' && cmd[1] == 't') {     /* stop rule change size previous */
            sk_rule r;
            double change, size, previous;
            rule(&r);
            change = num();
            size = num();
            previous = num();
            printf("stop %d\n", sk_newton_stop(&r, change, size, previous, 0));
        } else if (cmd[0] == 'n') {                        /* newton rule t evaluated mapped x0 x1 */
            sk_rule r;
            t_ctx c = {1.0, 0};
            int evaluated, mapped;
            double fj[6];
            rule(&r);
            c.t = num();
            evaluated = (int)num();
            mapped = (int)num();
            if (mapped) {
                static const int index[2] = {3, 1};
                for (i = 0; i < 5; ++i) {
                    x[i] = 100.0 + i;                      /* not unknowns: untouched */
                }
                x[3] = num();
                x[1] = num();
                if (evaluated) {
                    t_system_mapped(&c, x, fj);
                }
                status = sk_newton_solve(t_system_mapped, &c, 2, index, &r, NULL, x, fj,
                                         evaluated);
                printf("status %d\n", status);
                print("x", x, 5);
            } else {
                read(x, 2);
                if (evaluated) {
                    t_system(&c, x, fj);
                }
                status = sk_newton_solve(t_system, &c, 2, NULL, &r, NULL, x, fj, evaluated);
                printf("status %d\n", status);
                print("x", x, 2);
            }
        } else if (cmd[0] == 'q') {                        /* quiet rule residual: t_noisy */
            sk_rule r;
            t_ctx c = {0.0, 0};
            const double scale[1] = {1.0};
            double fj[2];
            rule(&r);
            r.residual = num();
            x[0] = 0.0;
            status = sk_newton_solve(t_noisy, &c, 1, NULL, &r, scale, x, fj, 0);
            printf("status %d evaluations %d\n", status, c.stages);
        } else if (cmd[0] == 'c' && cmd[1] == 'o') {     /* continuation rule top step */
            sk_rule r;
            t_ctx c = {0.0, 0};
            double fj[6], top, step;
            int steps;
            rule(&r);
            top = num();
            step = num();
            steps = sk_steps(top, step);
            x[0] = 2.0;
            x[1] = 0.0;
            status = sk_continuation(t_stage, t_system, &c, steps, 2, NULL, &r, x, fj);
            printf("status %d steps %d stages %d t %.17g\n", status, steps, c.stages, c.t);
            print("x", x, 2);
        } else if (cmd[0] == 'w') {                        /* wrap x */
            double v = num();
            v = sk_wrap(v);
            print("x", &v, 1);
        } else if (cmd[0] == 'p') {                        /* pose closed level input p0 p1 */
            sk_mechanism mech = t_mechanism((int)num());
            double in[1], p[2], out[6], ang[6], lnk[3];
            int level = (int)num();
            in[0] = num();
            read(p, 2);
            status = sk_evaluate_pose(&mech, in, p, level, out, ang, lnk);
            printf("status %d\n", status);
            print("out", out, 6);
            print("angles", ang, 6);
            print("links", lnk, 3);
        } else if (cmd[0] == 'r') {                        /* rows closed level n inputs */
            sk_mechanism mech = t_mechanism((int)num());
            double in[8], out[48], ang[48], p[4] = {0.5, 1.0, 0.4, 1.5};
            int level = (int)num(), st[16], failed;
            n = (int)num();
            read(in, n);
            failed = sk_evaluate_rows(&mech, n, in, NULL, level, out, ang, st);
            printf("failed %d\n", failed);
            print("out", out, 6 * n);
            print("angles", ang, 6 * n);
            for (i = 0; i < n; ++i) {
                printf("%s%d", i ? " " : "status ", st[i]);
            }
            printf("\n");
            failed = sk_evaluate_grid(&mech, 2, p, n, in, level, out, st);
            printf("grid %d\n", failed);
            print("gout", out, 12 * n);
            for (i = 0; i < 2 * n; ++i) {
                printf("%s%d", i ? " " : "gstatus ", st[i]);
            }
            printf("\n");
        } else if (cmd[0] == 'd') {                        /* derivatives closed level in p0 p1 */
            sk_mechanism mech = t_mechanism((int)num());
            double in[1], p[2], values[6], dev[6], rig[6], only[4];
            int level = (int)num();
            in[0] = num();
            read(p, 2);
            status = sk_sensitivity_full(&mech, in, p, level, values, dev, rig);
            printf("status %d\n", status);
            print("values", values, 6);
            print("dev", dev, 6);
            print("rig", rig, 6);
            status = sk_sensitivity_params(&mech, in, p, level, only);
            printf("status %d\n", status);
            print("only", only, 4);
            status = sk_sensitivity_rows(&mech, 1, in, p, level, values, dev, NULL, NULL);
            printf("failed %d\n", status);
            print("rows", dev, 6);
        } else {
            fprintf(stderr, "unknown command %s\n", cmd);
            return 2;
        }
        fflush(stdout);
    }
    return 0;
}
