/* tsf_runtime.h: the C99 runtime of the controllers tsfc generates.
 *
 * Part of tsf-runtime (runtime/c in the tsfc repository). `tsfc compile
 * --emit c` writes this file and tsf_runtime.c, byte for byte, next to the
 * generated controller and sensor files: compile and link tsf_runtime.c
 * once per image, however many controllers it holds.
 *
 * The C counterpart of the Rust crate tsf-runtime, operation by operation in
 * the Rust runtime's order (runtime/README.md): memberships, firing
 * strengths, the nearest-rule fallback, blend, saturation, the trigger state
 * machines and the runtime's own atan. Static memory only: no malloc, no
 * recursion, no global mutable state; arrays are passed with their lengths.
 *
 * Both precisions live in one image, named like libm: tsf_<f> works on
 * double and tsf_<f>f on float (types likewise: tsf_term and tsf_termf).
 * Generated code picks its instance with TSF_REAL_FN(<its real type>, name).
 *
 * Elementary functions: in double, tsf_exp, tsf_sin, tsf_cos, tsf_sinc,
 * tsf_exprel and tsf_atan are tsf-runtime's math::exp etc. bit for bit (its
 * fdlibm-style arithmetic, with Cody-Waite and Payne-Hanek reduction, no
 * libm call); tsf_sqrt and tsf_fabs are C's sqrt and fabs (correctly rounded
 * and exact, so the same bits). In float, every tsf_<f>f is tsf-runtime's
 * binary32 math::<f>f bit for bit, evaluated in float arithmetic only
 * (sqrtf and fabsf are C's, correctly rounded), so a float build links no
 * double-precision routine. Products
 * are separate statements, so contraction within an expression cannot fuse
 * them; for bit-exact runtime order also avoid contraction across statements
 * (GCC outside ISO modes: -ffp-contract=off).
 */

#ifndef TSF_RUNTIME_H
#define TSF_RUNTIME_H

#include <float.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Flag bits of a control step, identical to tsf_runtime::Flags. */
#define TSF_FLAG_NO_RULE_FIRED 1u
#define TSF_FLAG_STATE_NONFINITE 2u
#define TSF_FLAG_PREMISE_NONFINITE 4u
#define TSF_FLAG_COMMAND_NONFINITE 8u
#define TSF_FLAG_SATURATED 16u
#define TSF_FLAG_MODE_OUT_OF_RANGE 32u
#define TSF_FLAG_ESTIMATE_RESET 64u

/* TSF_REAL_FN(double, tsf_dot) is tsf_dot, TSF_REAL_FN(float, tsf_dot) is
   tsf_dotf; the type may be a macro expanding to double or float. */
#define TSF_PASTE(a, b) TSF_PASTE_(a, b)
#define TSF_PASTE_(a, b) a##b
#define TSF_SUFFIX_double
#define TSF_SUFFIX_float f
#define TSF_REAL_FN(real, name) TSF_PASTE(name, TSF_PASTE(TSF_SUFFIX_, real))

/* Largest finite value of the real type (DBL_MAX or FLT_MAX). */
#define TSF_MAX_double DBL_MAX
#define TSF_MAX_float FLT_MAX
#define TSF_REAL_MAX(real) TSF_PASTE(TSF_MAX_, real)

/* Kinds of rule-premise terms. */
enum { TSF_TERM_TRAP, TSF_TERM_GAUSS, TSF_TERM_SIGMOID, TSF_TERM_ABOUT };

/* One conjunct of a rule premise: trap(a, b, c, d) (tri(a, b, c) is
   trap(a, b, b, c)), gauss(center, sigma), sigmoid(slope, center) on z[var],
   or `about` the point about_points[point .. point + len] with width prm[0]
   on z[var .. var + len]. */
typedef struct tsf_term {
    int kind;
    int var;
    int len;
    int point;
    double prm[4];
} tsf_term;

/* tsf_term of a float controller. */
typedef struct tsf_termf {
    int kind;
    int var;
    int len;
    int point;
    float prm[4];
} tsf_termf;

/* The const tables of one controller; matrices are row-major. Each distinct
   premise term is listed once and evaluated once per step; a rule is the
   list of its terms' indices (its weight is their degrees' product). */
typedef struct tsf_controller {
    int n;                      /* states */
    int m;                      /* inputs */
    int p;                      /* premise components */
    int r;                      /* rules */
    int d;                      /* distinct premise terms */
    const tsf_term *terms;      /* the d distinct terms */
    const int *factors;         /* every rule's term indices, rule after rule */
    const int *rule_factors;    /* rule i: factors[rule_factors[i] .. rule_factors[i + 1]] */
    const double *about_points; /* operating points of `about` terms */
    const double *centres;      /* r rows of max(p, 1): rule centres in premise space */
    const double *gains;        /* r blocks of m x n: the PDC gains F_j */
    const double *u_max;        /* m saturation levels (INFINITY = unlimited) */
} tsf_controller;

/* tsf_controller of a float controller. */
typedef struct tsf_controllerf {
    int n;
    int m;
    int p;
    int r;
    int d;
    const tsf_termf *terms;
    const int *factors;
    const int *rule_factors;
    const float *about_points;
    const float *centres;
    const float *gains;
    const float *u_max;
} tsf_controllerf;

/* Parameters of the adaptive threshold law (Xu & Huang 2020): after each
   transmission but the first, nu = min(max(nu (1 - (2 mu1/pi) atan(mu2
   (||e|| - mu3))), nu_min), nu_max); a NaN candidate gives nu_min, and
   nu_max < nu_min keeps nu_min. nu_max = TSF_REAL_MAX(real) is
   tsf_runtime::AdaptiveTrigger::new, anything else `with_max(nu_max)`. */
typedef struct tsf_adaptive_law {
    double mu1;
    double mu2;
    double mu3;
    double nu_min;
    double nu_max;
} tsf_adaptive_law;

/* tsf_adaptive_law of a float trigger. */
typedef struct tsf_adaptive_lawf {
    float mu1;
    float mu2;
    float mu3;
    float nu_min;
    float nu_max;
} tsf_adaptive_lawf;

/* Elementary functions of premise code (see the top of this file).
   tsf_sinc(v) = sin(v)/v, 1 - v*v/6 for |v| < 2^-13 (math::SINC_SMALL).
   tsf_exprel(v) = (e^v - 1)/v, 1 at 0: for |v| < 0.5 (math::EXPREL_SMALL)
   the runtime's degree-14 Taylor polynomial, otherwise (tsf_exp(v) - 1)/v;
   +inf -> +inf, -inf -> 0. All bit for bit the Rust runtime's. */
double tsf_exp(double v);
double tsf_sqrt(double v);
double tsf_sin(double v);
double tsf_cos(double v);
double tsf_fabs(double v);
double tsf_sinc(double v);
double tsf_exprel(double v);
double tsf_atan(double v);
float tsf_expf(float v);
float tsf_sqrtf(float v);
float tsf_sinf(float v);
float tsf_cosf(float v);
float tsf_fabsf(float v);
float tsf_sincf(float v);
float tsf_exprelf(float v);
float tsf_atanf(float v);

/* sum_k a[k] b[k], accumulated in index order from the first product (0 if
   n <= 0). */
double tsf_dot(const double *a, const double *b, int n);
float tsf_dotf(const float *a, const float *b, int n);

/* One control step of tsf_runtime::FactoredController::step_with_premises
   on state x (c->n values) and premise vector z (c->p values): writes the
   normalised firing strengths h (c->r values) and the saturated command u
   (c->m values) and returns the TSF_FLAG_* bits; deg is scratch space for
   the c->d term degrees. A NaN or infinite x or z gives u = 0, h = 0; when
   no rule fires, the nearest rule centre's gain is used alone. */
uint8_t tsf_step_with_premises(const tsf_controller *c, const double *x, const double *z,
                               double *deg, double *h, double *u);
uint8_t tsf_step_with_premisesf(const tsf_controllerf *c, const float *x, const float *z,
                                float *deg, float *h, float *u);

/* Observer-based controller (tsf_runtime::Observer): the controller c on
   the estimate xhat and the exactly discretized fuzzy observer of every
   rule; matrices row-major. */
typedef struct tsf_observer {
    const tsf_controller *ctl; /* premises, rules, gains F_j, saturation */
    int q;                     /* measured outputs */
    const double *output_map;  /* n x q: premises read v = S y; NULL: v = xhat */
    const double *phi;         /* r blocks of n x n: expm((A_i - L_i C) T) */
    const double *gu;          /* r blocks of n x m: int_0^T expm(..) ds B_i */
    const double *gy;          /* r blocks of n x q: int_0^T expm(..) ds L_i */
} tsf_observer;

/* tsf_observer of a float controller. */
typedef struct tsf_observerf {
    const tsf_controllerf *ctl;
    int q;
    const float *output_map;
    const float *phi;
    const float *gu;
    const float *gy;
} tsf_observerf;

/* The vector v (ctl->n values) the premises are computed from: S y when
   output_map is set (each component tsf_dot), else xhat. */
void tsf_observer_premise_state(const tsf_observer *o, const double *xhat, const double *y,
                                double *v);
void tsf_observer_premise_statef(const tsf_observerf *o, const float *xhat, const float *y,
                                 float *v);

/* One step of tsf_runtime::Observer::step_with_premises: with premises z
   (ctl->p values, from tsf_observer_premise_state), writes h (ctl->r) and
   u_k (ctl->m) as tsf_step_with_premises on the estimate xhat (ctl->n), then
   advances xhat to sum_i h_i ((Phi_i xhat + Gu_i u) + Gy_i y); deg (ctl->d)
   and next (ctl->n) are scratch. A NaN or infinite y or xhat
   (TSF_FLAG_STATE_NONFINITE) or z (TSF_FLAG_PREMISE_NONFINITE) gives u = 0,
   h = 0 and keeps the estimate; a non-finite estimate, before or after the
   update, is reset to 0 (TSF_FLAG_ESTIMATE_RESET). */
uint8_t tsf_observer_step(const tsf_observer *o, double *xhat, const double *y, const double *z,
                          double *deg, double *h, double *u, double *next);
uint8_t tsf_observer_stepf(const tsf_observerf *o, float *xhat, const float *y, const float *z,
                           float *deg, float *h, float *u, float *next);

/* Model-reference adaptive T-S law (tsf_runtime::adaptive; Wang, Gao & He
   2013, several inputs), double only. With s = C x, p = P (s - s_m):
   u_k = ((A_m (s - r))_k - sum_i h_i a_ik'x - d sat(p_k / layer)) / sum_i h_i b_ik,
   then over dt (explicit Euler, projection onto each box after the step):
   a_ik += rate_a dt h_i x p_k, b_ik += rate_b dt h_i u_k p_k,
   d += rate_d dt sum_k |p_k|, s_m += dt A_m (s_m - r). A rate of 0 keeps the
   quantity. */

/* Most inputs of an adaptive law (as tsf_runtime::adaptive::MAX_INPUTS). */
#define TSF_MRAC_MAX_INPUTS 8
/* Status of tsf_mrac_step: done; a dimension out of range (u = 0); a NaN or
   infinite input, strength, step or command (u = 0). Refused steps leave the
   estimates and the reference model unchanged. */
#define TSF_MRAC_OK 0
#define TSF_MRAC_SHAPE 1
#define TSF_MRAC_NONFINITE 2

/* Rate and projection box of one adapted quantity. */
typedef struct tsf_adaptation {
    double rate; /* 0: not adapted */
    double lo;
    double hi;
} tsf_adaptation;

/* The const tables of an adaptive law; matrices row-major. */
typedef struct tsf_mrac_law {
    int n;           /* states */
    int m;           /* inputs = error components (<= TSF_MRAC_MAX_INPUTS) */
    int r;           /* rules */
    const double *c;   /* m x n: the error signal s = C x */
    const double *a_m; /* m x m: the reference model */
    const double *p;   /* m x m: A_m'P + P A_m = -Q */
    tsf_adaptation a;  /* a_ik: r x m x n */
    tsf_adaptation b;  /* b_ik: r x m */
    tsf_adaptation d;  /* d */
    double layer;      /* boundary layer (> 0) */
} tsf_mrac_law;

/* One step of the law: writes u (m values) from x (n), the normalised
   strengths h (r) and the reference r (m), then advances the caller's
   estimates a_hat (r x m x n), b_hat (r x m), *d_hat and the reference-model
   state s_m (m) over dt; work is scratch space of 2 m values. Returns a
   TSF_MRAC_* status. The strengths come from tsf_step_with_premises on a
   descriptor with m = 0 (no gains, no command). */
int tsf_mrac_step(const tsf_mrac_law *law, double *a_hat, double *b_hat, double *d_hat,
                  double *s_m, const double *x, const double *h, const double *r, double dt,
                  double *u, double *work);

/* The gain set of `mode` among k Markov-switching modes
   (tsf_runtime::select_mode): mode itself when mode < k, else 0 with
   TSF_FLAG_MODE_OUT_OF_RANGE or-ed into *flags. */
int tsf_select_mode(uint8_t mode, int k, uint8_t *flags);

/* Periodic trigger: transmit on the first tick and then every `every` ticks
   (0 acts as 1); *count starts at 0. */
int tsf_periodic_decide(uint32_t *count, uint32_t every);

/* Relative trigger (Xu & Huang 2020, condition (10) with a fixed nu):
   transmit iff e'U e >= nu x_k'U x_k, e = x - x_k, x_k = last (n values,
   valid when *has_last), U = weight (n x n, row-major). The first call and
   a comparison involving NaN transmit; on transmission x becomes last. The
   jump e (zeros on the first call) is written to e (n values). */
int tsf_relative_decide(const double *weight, double nu, double *last, int *has_last,
                        const double *x, double *e, int n);
int tsf_relative_decidef(const float *weight, float nu, float *last, int *has_last,
                         const float *x, float *e, int n);

/* Adaptive trigger: the relative decision with threshold *nu, then the law's
   update of *nu after every transmission but the first. e is scratch space
   of n values. */
int tsf_adaptive_decide(const tsf_adaptive_law *law, const double *weight, double *nu,
                        double *last, int *has_last, const double *x, double *e, int n);
int tsf_adaptive_decidef(const tsf_adaptive_lawf *law, const float *weight, float *nu,
                         float *last, int *has_last, const float *x, float *e, int n);

/* Mixed trigger (Amrr et al. 2019, condition (28)): transmit iff
   ||sigma_k - sigma|| >= beta ||sigma|| + rho, sigma_k = last (n values,
   valid when *has_last); the first call and NaN comparisons transmit, and
   on transmission sigma becomes last. d is scratch space of n values. */
int tsf_mixed_decide(double beta, double rho, double *last, int *has_last,
                     const double *sigma, double *d, int n);
int tsf_mixed_decidef(float beta, float rho, float *last, int *has_last,
                      const float *sigma, float *d, int n);

#ifdef __cplusplus
}
#endif

#endif /* TSF_RUNTIME_H */
