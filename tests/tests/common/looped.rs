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

/// The controller gains F_j of the report (`gains[j].F`).
pub fn report_gains(report: &Value) -> Vec<DMatrix<f64>> {
    let gains = report["gains"].as_array().expect("gains");
    gains.iter().map(|g| mat(&g["F"])).collect()
}

/// The report of a compile that must certify, as JSON.
pub fn certified((_, c): (tsfc::model::TsModel, tsfc::driver::compile::Compiled)) -> Value {
    assert_eq!(
        c.status,
        tsfc::driver::compile::Status::Certified,
        "{:?}",
        c.report.diagnosis
    );
    serde_json::to_value(&c.report).expect("report json")
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
    l: [DMatrix<f64>; 2],
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
            l: [l1, l2],
            c,
            n,
            models,
            steps,
        }
    }

    /// Observer rule `j`'s step (Phi_j, Gu_j, Gy_j).
    pub fn step(&self, j: usize) -> &(DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        &self.steps[j]
    }

    /// The measured output map C.
    pub fn c(&self) -> &DMatrix<f64> {
        &self.c
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
        plant: &(DMatrix<f64>, DMatrix<f64>),
        k: &DMatrix<f64>,
        phi: f64,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        self.blocks_with(plant, k, phi, None)
    }

    /// The blocks with an H-inf channel: psi = [xi(t); xi(t_k); w], the flow
    /// gains Dbar w, Xi gains z'z - g w'w with z = Zx xi + Zu u_k + Zw w
    /// (u_k the first rows of K xi(t_k)).
    pub fn blocks_with(
        &self,
        plant: &(DMatrix<f64>, DMatrix<f64>),
        k: &DMatrix<f64>,
        phi: f64,
        channel: Option<&Channel>,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        self.blocks_full(plant, k, phi, channel, None)
    }

    /// The blocks with the saturation ACTIVE: psi = [xi(t); xi(t_k); dz],
    /// the dead zone dz = u_k - sat(u_k) held with u_k, fed to the plant and
    /// to the observer (it runs on the clipped command): the flow gains
    /// -Bbar [I; Gu_j / T] dz, and Xi the sector term
    /// He(dz' T G xi(t_k)) - 2 dz' T dz (Tarbouriech et al. 2011, Lemma 1.6)
    /// with `sector` = (T, G) of the pair (observer rule `j`, gain `f`).
    pub fn blocks_sat(
        &self,
        plant: &(DMatrix<f64>, DMatrix<f64>),
        (j, f): (usize, &DMatrix<f64>),
        phi: f64,
        sector: (&DMatrix<f64>, &DMatrix<f64>),
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        let (n, m) = (self.n, f.nrows());
        let mut map = DMatrix::zeros(m + n, m);
        map.view_mut((0, 0), (m, m)).fill_with_identity();
        map.view_mut((m, 0), (n, m))
            .copy_from(&(&self.steps[j].1 / self.t));
        let k = self.gain(j, f);
        self.blocks_full(plant, &k, phi, None, Some((&map, sector.0, sector.1)))
    }

    /// The blocks with the optional H-inf channel and dead-zone column (its
    /// map into the held input, T, G).
    fn blocks_full(
        &self,
        (abar, bbar): &(DMatrix<f64>, DMatrix<f64>),
        k: &DMatrix<f64>,
        phi: f64,
        channel: Option<&Channel>,
        dz: Option<(&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>)>,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        let (t, big) = (self.t, 2 * self.n);
        let q = channel.map_or(0, |c| c.d.ncols());
        let md = dz.map_or(0, |(map, _, _)| map.ncols());
        let size = 2 * big + q + md;
        let pick = |at: usize, len: usize| {
            DMatrix::from_fn(len, size, |r, c| f64::from(u8::from(c == r + at)))
        };
        let (ex, es, ew) = (pick(0, big), pick(big, big), pick(2 * big, q));
        let (p, y) = (&self.p, &self.y);
        let free = ex.transpose() * &self.l[0] + es.transpose() * &self.l[1];
        let mut flow = abar * &ex + bbar * k * &es;
        let he = |q: DMatrix<f64>| &q + q.transpose();
        let mut xi = ex.transpose() * p * &ex * phi + he(&free * (&ex - &es));
        if let Some(ch) = channel {
            flow += &ch.d * &ew;
            let m = ch.zu.ncols();
            let z = &ch.zx * &ex + &ch.zu * k.rows(0, m) * &es + &ch.zw * &ew;
            xi += z.transpose() * z - ew.transpose() * &ew * ch.g;
        }
        if let Some((map, tm, g)) = dz {
            let edz = pick(2 * big + q, md);
            flow -= bbar * map * &edz;
            xi += he(edz.transpose() * tm * g * &es) - edz.transpose() * tm * &edz * 2.0;
        }
        xi += he(ex.transpose() * p * &flow);
        let r1 = &xi + flow.transpose() * y * &flow * t;
        let mut r2 = DMatrix::zeros(size + big, size + big);
        r2.view_mut((0, 0), (size, size)).copy_from(&xi);
        r2.view_mut((0, size), (size, big))
            .copy_from(&(&free * t.sqrt()));
        r2.view_mut((size, 0), (big, size))
            .copy_from(&(free.transpose() * t.sqrt()));
        r2.view_mut((size, size), (big, big))
            .copy_from(&(-(-phi * t).exp() * y));
        (r1, r2)
    }
}

/// The worst eigenvalue of the paired conditions of the drift route with the
/// drift `delta` of h_2 (two rules: the term delta (A_2 - A_1, B_2 - B_1))
/// at both signs: Lambda_jj and Lambda_jl + Lambda_lj, plant j drifted,
/// `blocks(plant, j, l)` the (r = 1, r = 2) blocks of observer rule j and
/// controller rule l.
pub fn worst_paired(
    lp: &Looped,
    delta: f64,
    mut blocks: impl FnMut(&(DMatrix<f64>, DMatrix<f64>), usize, usize) -> (DMatrix<f64>, DMatrix<f64>),
) -> f64 {
    let r = lp.rules();
    let (a1, b1) = lp.models[0].clone();
    let mut worst = f64::NEG_INFINITY;
    for sign in [-1.0, 1.0] {
        let d = sign * delta;
        let plant = |j: usize| {
            let (a, b) = &lp.models[j];
            let (a2, b2) = &lp.models[1];
            lp.plant(&(a + (a2 - &a1) * d), &(b + (b2 - &b1) * d))
        };
        for j in 0..r {
            for l in j..r {
                let (mut r1, mut r2) = blocks(&plant(j), j, l);
                if l != j {
                    let (s1, s2) = blocks(&plant(l), l, j);
                    r1 += s1;
                    r2 += s2;
                }
                worst = worst.max(max_eig(&r1)).max(max_eig(&r2));
            }
        }
    }
    worst
}

/// The H-inf channel of [`Looped::blocks_with`].
pub struct Channel {
    /// Dbar (2n x q): the disturbance columns on xi.
    pub d: DMatrix<f64>,
    /// z's map of xi.
    pub zx: DMatrix<f64>,
    /// z's map of u_k.
    pub zu: DMatrix<f64>,
    /// z's map of w.
    pub zw: DMatrix<f64>,
    /// g = gamma^2.
    pub g: f64,
}
