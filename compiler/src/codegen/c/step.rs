//! The controller's table-driven step (`emit c(style = table)`),
//! accessors and trigger state machines in `<name>.c`: thin wrappers that
//! hand this controller's tables and dimensions to the runtime
//! (`tsf_runtime.c`), which does the arithmetic. The straight-line step is
//! [`super::straight`].

use super::Gen;

impl Gen<'_> {
    /// The table-driven step: `<name>_step_with_premises` hands the
    /// descriptor to the runtime's `tsf_step_with_premises`.
    pub(super) fn step(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        let pd = self.pd;
        let dd = self.t.factored.terms.len().max(1);
        let (mode_param, mode_arg, call) = match self.t.modes {
            Some(_) => (
                "uint8_t mode, ",
                "mode, ",
                format!("uint8_t flags = 0u;\n    const int a = tsf_select_mode(mode, {u}K, &flags);\n    s->flags = (uint8_t)({u}RT(tsf_step_with_premises)(&{p}tables[a], x, z, deg, s->h, u) | flags);"),
            ),
            None => (
                "",
                "",
                format!("s->flags = {u}RT(tsf_step_with_premises)(&{p}tables, x, z, deg, s->h, u);"),
            ),
        };
        format!(
            r#"void {p}step_with_premises({p}t *s, {mode_param}const {real} x[{u}N], const {real} z[], {real} u[{u}M]) {{
    {real} deg[{dd}]; /* degrees of the distinct premise terms */
    {call}
}}

void {p}step({p}t *s, {mode_param}const {real} x[{u}N], {real} u[{u}M]) {{
    {real} z[{pd}];
    {p}premises(x, z);
    {p}step_with_premises(s, {mode_arg}x, z, u);
}}

"#
        )
    }

    /// `<name>_init`: h = 0, no flags.
    pub(super) fn init(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        format!(
            r#"void {p}init({p}t *s) {{
    int i;
    for (i = 0; i < {u}R; i++) {{
        s->h[i] = {u}C(0);
    }}
    s->flags = 0;
}}

"#
        )
    }

    /// The accessors of the controller state.
    pub(super) fn accessors(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        format!(
            r#"uint8_t {p}flags(const {p}t *s) {{
    return s->flags;
}}

int {p}is_fault(const {p}t *s) {{
    return (s->flags & ({u}FLAG_STATE_NONFINITE | {u}FLAG_PREMISE_NONFINITE)) != 0u;
}}

int {p}no_rule_fired(const {p}t *s) {{
    return (s->flags & {u}FLAG_NO_RULE_FIRED) != 0u;
}}

int {p}saturated(const {p}t *s) {{
    return (s->flags & {u}FLAG_SATURATED) != 0u;
}}

const {real} *{p}strengths(const {p}t *s) {{
    return s->h;
}}

"#
        )
    }

    /// The periodic, relative, adaptive and mixed triggers (tsf-runtime's
    /// `trigger` module) on this controller's state dimension.
    pub(super) fn triggers(&self) -> String {
        let (p, u) = (&self.p, &self.u);
        let real = format!("{u}REAL");
        format!(
            r#"void {p}periodic_init({p}periodic_t *t, uint32_t every) {{
    t->every = every;
    t->count = 0;
}}

int {p}periodic_decide({p}periodic_t *t) {{
    return tsf_periodic_decide(&t->count, t->every);
}}

void {p}relative_init({p}relative_t *t, const {real} *weight, {real} nu) {{
    int k;
    for (k = 0; k < {u}N * {u}N; k++) {{
        t->weight[k] = weight[k];
    }}
    for (k = 0; k < {u}N; k++) {{
        t->last[k] = {u}C(0);
    }}
    t->nu = nu;
    t->has_last = 0;
}}

int {p}relative_decide({p}relative_t *t, const {real} x[{u}N]) {{
    {real} e[{u}N];
    return {u}RT(tsf_relative_decide)(t->weight, t->nu, t->last, &t->has_last, x, e, {u}N);
}}

void {p}adaptive_init({p}adaptive_t *t, const {real} *weight, {real} nu_min, {real} mu1, {real} mu2, {real} mu3) {{
    {p}relative_init(&t->inner, weight, nu_min);
    t->mu1 = mu1;
    t->mu2 = mu2;
    t->mu3 = mu3;
    t->nu_min = nu_min;
}}

int {p}adaptive_decide({p}adaptive_t *t, const {real} x[{u}N]) {{
    const {u}RT(tsf_adaptive_law) law = {{t->mu1, t->mu2, t->mu3, t->nu_min, TSF_REAL_MAX({real})}};
    {real} e[{u}N];
    return {u}RT(tsf_adaptive_decide)(&law, t->inner.weight, &t->inner.nu, t->inner.last,
        &t->inner.has_last, x, e, {u}N);
}}

{real} {p}adaptive_nu(const {p}adaptive_t *t) {{
    return t->inner.nu;
}}

void {p}mixed_init({p}mixed_t *t, {real} beta, {real} rho) {{
    int k;
    t->beta = beta;
    t->rho = rho;
    for (k = 0; k < {u}N; k++) {{
        t->last[k] = {u}C(0);
    }}
    t->has_last = 0;
}}

int {p}mixed_decide({p}mixed_t *t, const {real} sigma[{u}N]) {{
    {real} d[{u}N];
    return {u}RT(tsf_mixed_decide)(t->beta, t->rho, t->last, &t->has_last, sigma, d, {u}N);
}}
"#
        )
    }
}
