//! The looped-functional conditions of the sampled observer loop rebuilt
//! from a report alone (shared by `observer_shipped` and `observer_drift`):
//! Abar_i = diag(A_i, 0), Bbar_i = diag(B_i, I), K_jl = [0, F_l; Gy_j C / T,
//! (Phi_j - I) / T + Gu_j F_l / T] with (Phi_j, Gu_j, Gy_j) the ZOH of the
//! reported L_j (Van Loan's block exponential, nalgebra's `exp`), and the
//! blocks r = 1: Xi + T Phi' Y Phi, r = 2: [Xi, sqrt(T)(Ex' L1 + Es' L2);
//! *, -e^{-phi T} Y] with psi = [xi(t); xi(t_k)], Phi = Abar Ex + Bbar K Es,
//! Xi = He(Ex' P Phi) + phi Ex' P Ex + He((Ex' L1 + Es' L2)(Ex - Es)).

use nalgebra::DMatrix;
use serde_json::Value;

/// A matrix of the report (rows).
pub fn mat(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = serde_json::from_value(v.clone()).expect("a matrix");
    let (r, c) = (rows.len(), rows.first().map_or(0, Vec::len));
    DMatrix::from_fn(r, c, |i, j| rows[i][j])
}

/// The exact zero-order hold of x' = A x + G w over `t`: (Phi, Gamma).
pub fn zoh(a: &DMatrix<f64>, g: &DMatrix<f64>, t: f64) -> (DMatrix<f64>, DMatrix<f64>) {
    let (n, k) = (a.nrows(), g.ncols());
    let mut m = DMatrix::zeros(n + k, n + k);
    m.view_mut((0, 0), (n, n)).copy_from(&(a * t));
    m.view_mut((0, n), (n, k)).copy_from(&(g * t));
    let e = m.exp();
    (
        e.view((0, 0), (n, n)).into_owned(),
        e.view((0, n), (n, k)).into_owned(),
    )
}

/// The largest eigenvalue of the symmetric part of `m`.
pub fn max_eig(m: &DMatrix<f64>) -> f64 {
    let s = (m + m.transpose()) / 2.0;
    s.symmetric_eigenvalues().max()
}

/// The report's looped functional and loop data.
pub struct Looped {
    /// The period T.
    pub t: f64,
    p: DMatrix<f64>,
    y: DMatrix<f64>,
    free: DMatrix<f64>,
    ex: DMatrix<f64>,
    es: DMatrix<f64>,
    c: DMatrix<f64>,
    n: usize,
    /// (A_i, B_i) of every rule.
    pub models: Vec<(DMatrix<f64>, DMatrix<f64>)>,
    steps: Vec<(DMatrix<f64>, DMatrix<f64>, DMatrix<f64>)>,
}

impl Looped {
    /// The data of `report` (its `sampled_loop`, `observer`, `local_models`).
    pub fn of(report: &Value) -> Self {
        let s = &report["sampled_loop"];
        let t = s["sampling"][0].as_f64().expect("T");
        let (p, y) = (mat(&s["P"]), mat(&s["Y"]));
        assert!(-max_eig(&-&p) > 0.0 && -max_eig(&-&y) > 0.0, "P, Y > 0");
        let (l1, l2) = (mat(&s["L"][0]), mat(&s["L"][1]));
        let c = mat(&report["observer"]["C"]);
        let n = c.ncols();
        let big = 2 * n;
        let ex = DMatrix::from_fn(big, 2 * big, |r, k| f64::from(u8::from(k == r)));
        let es = DMatrix::from_fn(big, 2 * big, |r, k| f64::from(u8::from(k == r + big)));
        let free = ex.transpose() * &l1 + es.transpose() * &l2;
        let models: Vec<_> = report["local_models"]
            .as_array()
            .expect("local models")
            .iter()
            .map(|md| (mat(&md["A"]), mat(&md["B"])))
            .collect();
        let m = models[0].1.ncols();
        let steps = models
            .iter()
            .zip(report["observer"]["gains"].as_array().expect("L"))
            .map(|((a, b), lj)| {
                let l = mat(&lj["L"]);
                let mut g = DMatrix::zeros(n, m + c.nrows());
                g.view_mut((0, 0), (n, m)).copy_from(b);
                g.view_mut((0, m), (n, c.nrows())).copy_from(&l);
                let (ph, gam) = zoh(&(a - &l * &c), &g, t);
                (
                    ph,
                    gam.columns(0, m).into_owned(),
                    gam.columns(m, c.nrows()).into_owned(),
                )
            })
            .collect();
        Looped {
            t,
            p,
            y,
            free,
            ex,
            es,
            c,
            n,
            models,
            steps,
        }
    }

    /// The number of rules.
    pub fn rules(&self) -> usize {
        self.models.len()
    }

    /// (Abar, Bbar) of the plant (A, B).
    pub fn plant(&self, a: &DMatrix<f64>, b: &DMatrix<f64>) -> (DMatrix<f64>, DMatrix<f64>) {
        let (n, m) = (self.n, b.ncols());
        let mut abar = DMatrix::zeros(2 * n, 2 * n);
        abar.view_mut((0, 0), (n, n)).copy_from(a);
        let mut bbar = DMatrix::zeros(2 * n, m + n);
        bbar.view_mut((0, 0), (n, m)).copy_from(b);
        bbar.view_mut((n, m), (n, n)).fill_with_identity();
        (abar, bbar)
    }

    /// K_jl for observer rule `j` and the controller gain `f`.
    pub fn gain(&self, j: usize, f: &DMatrix<f64>) -> DMatrix<f64> {
        let (n, m, t) = (self.n, f.nrows(), self.t);
        let (ph, gu, gy) = &self.steps[j];
        let mut k = DMatrix::zeros(m + n, 2 * n);
        k.view_mut((0, n), (m, n)).copy_from(f);
        k.view_mut((m, 0), (n, n)).copy_from(&(gy * &self.c / t));
        let drift = (ph - DMatrix::identity(n, n) + gu * f) / t;
        k.view_mut((m, n), (n, n)).copy_from(&drift);
        k
    }

    /// The blocks (r = 1, r = 2) of the vertex (Abar, Bbar, K) at `phi`.
    pub fn blocks(
        &self,
        (abar, bbar): &(DMatrix<f64>, DMatrix<f64>),
        k: &DMatrix<f64>,
        phi: f64,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        let (t, big) = (self.t, 2 * self.n);
        let (ex, es, p, y) = (&self.ex, &self.es, &self.p, &self.y);
        let flow = abar * ex + bbar * k * es;
        let he = |q: DMatrix<f64>| &q + q.transpose();
        let xi = he(ex.transpose() * p * &flow)
            + ex.transpose() * p * ex * phi
            + he(&self.free * (ex - es));
        let r1 = &xi + flow.transpose() * y * &flow * t;
        let mut r2 = DMatrix::zeros(3 * big, 3 * big);
        r2.view_mut((0, 0), (2 * big, 2 * big)).copy_from(&xi);
        r2.view_mut((0, 2 * big), (2 * big, big))
            .copy_from(&(&self.free * t.sqrt()));
        r2.view_mut((2 * big, 0), (big, 2 * big))
            .copy_from(&(self.free.transpose() * t.sqrt()));
        r2.view_mut((2 * big, 2 * big), (big, big))
            .copy_from(&(-(-phi * t).exp() * y));
        (r1, r2)
    }
}
