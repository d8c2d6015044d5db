//! Why no plant claim of the regional Xu & Huang spec contains the paper's
//! x(0) (issue 34), checked with exact arithmetic where it is a proof
//! (docs/language.md, "The plant claim").
//!
//! 1. No region at all carries the claim by the norm-bounded route: at rest
//!    the rules' blend differs from A(0) by more than the stability radius
//!    sigma_min(A_h(0) + B K) of the blended closed loop, so some admissible
//!    dA makes it singular and the robust conditions (continuous or sampled)
//!    have no solution, for any P and multipliers, on any region (every
//!    region contains the origin).
//! 2. The regional certificate keeps E(P, c) where the actuator is linear
//!    (G = 0), and x(0) is far outside it.
//! 3. Quadratic V is not the obstacle: the test the issue proposes, "is there
//!    P > 0 with 2 x_k' P f(x_k) <= 0 at sampled states x_k" for the declared
//!    plant A(x) x + B sat(u) with the shipped gain u = -J (0.36 w + 0.0648 q)
//!    (the continuous loop, actuator saturating at 2 N m), has a solution for
//!    the states of the simulated trajectory from x(0) (RK4, 10 ms, one per
//!    second for 120 s) and the 3^6 grid of the smallest box symmetric about
//!    0 that holds it: Clarabel finds P, and the test re-checks P > 0 and
//!    every <P, S_k> <= 0 (S_k = z_k f_k' + f_k z_k') in interval arithmetic
//!    with outward rounding (each f64 operation widened by one ulp, an
//!    interval Cholesky factorization). So no Farkas certificate of
//!    infeasibility exists for those states: a nonnegative combination
//!    sum lambda_k S_k that is positive definite would give <P, M> > 0.
//!    This is a statement about finitely many states, not a certificate of the
//!    continuum (which would need the region of a claim and its bound).
//!
//! The coordinates z = [J w; q] (angular momentum, quaternion vector) avoid
//! J^-1; a quadratic V in z is one in x (z = diag(J, I) x).

use nalgebra::{DMatrix, Matrix3, Vector3};
use tsf_lmi::{Expr, Problem, Relation, SolveSettings};

/// The inertia of Section 4, kg m^2.
const J: [[f64; 3]; 3] = [[350.0, 3.0, 4.0], [3.0, 270.0, 10.0], [4.0, 10.0, 190.0]];
/// The paper's x(0) = [w; q] (specs/xu2020_regional.tsf).
const X0: [f64; 6] = [0.0, 0.0, 0.0, -0.3802, 0.2124, 0.5013];
/// The actuator limit, N m.
const U_BAR: f64 = 2.0;
/// The shipped gain u = -J (KW w + KQ q).
const KW: f64 = 0.36;
const KQ: f64 = 0.0648;

/// A closed interval [lo, hi], every operation rounded outward.
#[derive(Debug, Clone, Copy)]
struct Iv {
    lo: f64,
    hi: f64,
}

impl Iv {
    fn pt(v: f64) -> Iv {
        Iv { lo: v, hi: v }
    }
    fn out(lo: f64, hi: f64) -> Iv {
        Iv {
            lo: lo.next_down(),
            hi: hi.next_up(),
        }
    }
    fn add(self, o: Iv) -> Iv {
        Iv::out(self.lo + o.lo, self.hi + o.hi)
    }
    fn sub(self, o: Iv) -> Iv {
        Iv::out(self.lo - o.hi, self.hi - o.lo)
    }
    fn mul(self, o: Iv) -> Iv {
        let p = [
            self.lo * o.lo,
            self.lo * o.hi,
            self.hi * o.lo,
            self.hi * o.hi,
        ];
        let lo = p.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Iv::out(lo, hi)
    }
    fn div(self, o: Iv) -> Iv {
        assert!(o.lo > 0.0, "division by a positive interval only");
        let p = [
            self.lo / o.lo,
            self.lo / o.hi,
            self.hi / o.lo,
            self.hi / o.hi,
        ];
        let lo = p.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Iv::out(lo, hi)
    }
    fn sqrt(self) -> Iv {
        assert!(self.lo >= 0.0);
        Iv::out(self.lo.sqrt(), self.hi.sqrt()).clamp_lo(0.0)
    }
    fn clamp_lo(self, at: f64) -> Iv {
        Iv {
            lo: self.lo.max(at),
            hi: self.hi,
        }
    }
    /// sat to [-l, l] (monotone, so endpoint-wise).
    fn sat(self, l: f64) -> Iv {
        Iv {
            lo: self.lo.clamp(-l, l),
            hi: self.hi.clamp(-l, l),
        }
    }
}

/// The loop's state in the coordinates z = [J w; q] (angular momentum and
/// quaternion vector: no J^-1 is needed, and a quadratic V in z is one in x,
/// z = diag(J, I) x) with its derivative, both enclosed, from x = [w; q]
/// given exactly.
fn z_and_rate(x: &[f64; 6]) -> ([Iv; 6], [Iv; 6]) {
    let w = [Iv::pt(x[0]), Iv::pt(x[1]), Iv::pt(x[2])];
    let q = [Iv::pt(x[3]), Iv::pt(x[4]), Iv::pt(x[5])];
    let jv = |v: &[Iv; 3]| -> [Iv; 3] {
        std::array::from_fn(|r| (0..3).fold(Iv::pt(0.0), |s, c| s.add(Iv::pt(J[r][c]).mul(v[c]))))
    };
    let cross = |a: &[Iv; 3], b: &[Iv; 3]| -> [Iv; 3] {
        std::array::from_fn(|r| {
            let (i, k) = ((r + 1) % 3, (r + 2) % 3);
            a[i].mul(b[k]).sub(a[k].mul(b[i]))
        })
    };
    let p = jv(&w);
    // u = -J (KW w + KQ q), saturated per axis.
    let inner: [Iv; 3] = std::array::from_fn(|r| Iv::pt(KW).mul(w[r]).add(Iv::pt(KQ).mul(q[r])));
    let ju = jv(&inner);
    let u: [Iv; 3] = std::array::from_fn(|r| Iv::pt(0.0).sub(ju[r]).sat(U_BAR));
    // p' = -w x (J w) + sat(u); q' = 0.5 (sqrt(1 - q'q) w + q x w).
    let gyro = cross(&w, &p);
    let qq = (0..3).fold(Iv::pt(0.0), |s, r| s.add(q[r].mul(q[r])));
    let q0 = Iv::pt(1.0).sub(qq).sqrt();
    let qxw = cross(&q, &w);
    let half = Iv::pt(0.5);
    let z = [p[0], p[1], p[2], q[0], q[1], q[2]];
    let rate = std::array::from_fn(|r| match r {
        0..=2 => u[r].sub(gyro[r]),
        _ => half.mul(q0.mul(w[r - 3]).add(qxw[r - 3])),
    });
    (z, rate)
}

/// The same vector field in x (floating point, for the simulation only).
fn field(x: &[f64; 6]) -> [f64; 6] {
    let j = Matrix3::from_fn(|r, c| J[r][c]);
    let w = Vector3::new(x[0], x[1], x[2]);
    let q = Vector3::new(x[3], x[4], x[5]);
    let u = (-(j * (w * KW + q * KQ))).map(|v| v.clamp(-U_BAR, U_BAR));
    let wd = j.try_inverse().expect("J") * (u - w.cross(&(j * w)));
    let qd = (w * (1.0 - q.norm_squared()).sqrt() + q.cross(&w)) * 0.5;
    [wd[0], wd[1], wd[2], qd[0], qd[1], qd[2]]
}

/// States on the trajectory from x(0): RK4 with 10 ms steps, one per second.
fn trajectory(seconds: usize) -> Vec<[f64; 6]> {
    let dt = 0.01;
    let mut x = X0;
    let mut out = vec![x];
    let step = |x: &[f64; 6], k: &[f64; 6], s: f64| -> [f64; 6] {
        std::array::from_fn(|i| x[i] + s * k[i])
    };
    for _ in 0..seconds {
        for _ in 0..100 {
            let k1 = field(&x);
            let k2 = field(&step(&x, &k1, dt / 2.0));
            let k3 = field(&step(&x, &k2, dt / 2.0));
            let k4 = field(&step(&x, &k3, dt));
            x = std::array::from_fn(|i| {
                x[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            });
        }
        out.push(x);
    }
    out
}

/// S_k = z f' + f z' (interval), so that 2 z' P f = <P, S_k>.
fn s_matrix(z: &[Iv; 6], f: &[Iv; 6]) -> Vec<Vec<Iv>> {
    (0..6)
        .map(|r| (0..6).map(|c| z[r].mul(f[c]).add(f[r].mul(z[c]))).collect())
        .collect()
}

fn mid(m: &[Vec<Iv>]) -> DMatrix<f64> {
    DMatrix::from_fn(6, 6, |r, c| 0.5 * (m[r][c].lo + m[r][c].hi))
}

/// P >= I with 2 z_k' P f_k <= -ALPHA |z_k|^2 at every state, found by
/// Clarabel on the midpoints of the S_k (`None` when it finds none).
fn decreasing_p(s: &[Vec<Vec<Iv>>], z: &[[Iv; 6]]) -> Option<DMatrix<f64>> {
    let mut problem = Problem::new();
    let p = problem.symmetric("P", 6).expect("P");
    let id = DMatrix::identity(6, 6);
    let shifted = Expr::var(p)
        .sub(Expr::constant(&id).expect("I"))
        .expect("P - I");
    problem.psd("P >= I", shifted, 0.0).expect("psd");
    for (k, (sk, zk)) in s.iter().zip(z).enumerate() {
        let e = Expr::product(&id, p, &mid(sk))
            .and_then(Expr::trace)
            .expect("<P, S_k>");
        let norm2: f64 = zk.iter().map(|v| v.hi.abs().max(v.lo.abs()).powi(2)).sum();
        problem
            .add_scalar(&format!("decrease {k}"), e, Relation::Le, -ALPHA * norm2)
            .expect("decrease");
    }
    problem
        .minimize(Expr::var(p).trace().expect("tr"))
        .expect("objective");
    let sol = problem
        .solve(&SolveSettings::default())
        .expect("solver runs");
    sol.value(p).ok().cloned()
}

/// The decrease margin asked of the SDP, so that the exact re-check of
/// "<= 0" has room for the solver's tolerance.
const ALPHA: f64 = 1e-6;

/// The grid of `per` points per axis on the smallest box symmetric about 0
/// holding `states` (E(P, c) is symmetric: an ellipsoid holding x holds -x).
fn symmetric_grid(states: &[[f64; 6]], per: usize) -> Vec<[f64; 6]> {
    let mut top = [0.0f64; 6];
    for x in states {
        for i in 0..6 {
            top[i] = top[i].max(x[i].abs());
        }
    }
    (0..per.pow(6))
        .map(|mut k| {
            std::array::from_fn(|i| {
                let t = (k % per) as f64 / (per - 1) as f64;
                k /= per;
                top[i] * (2.0 * t - 1.0)
            })
        })
        .collect()
}

/// Whether every symmetric matrix in the interval matrix `m` is positive
/// definite: the interval Cholesky factorization succeeds with every pivot's
/// lower end positive (it encloses the factor of every member).
fn interval_cholesky_succeeds(m: &[Vec<Iv>]) -> Option<f64> {
    let n = m.len();
    let mut l = vec![vec![Iv::pt(0.0); n]; n];
    let mut smallest = f64::INFINITY;
    for j in 0..n {
        let d = l[j][..j]
            .iter()
            .fold(m[j][j], |d, ljk| d.sub(ljk.mul(*ljk)));
        if d.lo <= 0.0 {
            return None;
        }
        smallest = smallest.min(d.lo);
        let root = d.sqrt();
        l[j][j] = root;
        for i in j + 1..n {
            let s = l[i][..j]
                .iter()
                .zip(&l[j][..j])
                .fold(m[i][j], |s, (lik, ljk)| s.sub(lik.mul(*ljk)));
            l[i][j] = s.div(root);
        }
    }
    Some(smallest)
}

#[test]
fn the_paper_s_x0_is_outside_the_linear_region_of_the_shipped_gain() {
    // The regional certificate keeps E(P, c) where |u_s| <= 2 N m (G = 0);
    // u(x(0)) = -J KQ q(0) is far outside it.
    let (_, _) = z_and_rate(&X0);
    let q = [X0[3], X0[4], X0[5]];
    let u: Vec<f64> = (0..3)
        .map(|r| -(0..3).map(|c| J[r][c] * KQ * q[c]).sum::<f64>())
        .collect();
    let largest = u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(largest > 3.0 * U_BAR, "|u(x(0))| = {largest}");
}

#[test]
fn a_quadratic_v_decreases_at_every_sampled_state_so_no_farkas_certificate_exists() {
    let path = trajectory(120);
    let mut states = path.clone();
    // The origin is left out (V' = 0 there for every P).
    states.extend(
        symmetric_grid(&path, 3)
            .into_iter()
            .filter(|x| x.iter().any(|v| *v != 0.0)),
    );
    let (z, s): (Vec<_>, Vec<_>) = states
        .iter()
        .map(|x| {
            let (z, f) = z_and_rate(x);
            (z, s_matrix(&z, &f))
        })
        .unzip();
    let p = decreasing_p(&s, &z).expect("Clarabel finds P");
    // Exact re-check: P > 0 (interval Cholesky) and <P, S_k> <= 0 for every k,
    // with S_k enclosed and the products and sums rounded outward.
    let p_iv: Vec<Vec<Iv>> = (0..6)
        .map(|r| (0..6).map(|c| Iv::pt(p[(r, c)])).collect())
        .collect();
    assert!(interval_cholesky_succeeds(&p_iv).is_some(), "P > 0");
    let mut worst = f64::NEG_INFINITY;
    for sk in &s {
        let mut dot = Iv::pt(0.0);
        for r in 0..6 {
            for c in 0..6 {
                dot = dot.add(Iv::pt(p[(r, c)]).mul(sk[r][c]));
            }
        }
        worst = worst.max(dot.hi);
    }
    println!(
        "xu quadratic V: {} states ({} on the trajectory, {} on the symmetric box grid), max 2 z' P f <= {worst:.3e}, P diagonal {:?}",
        states.len(),
        path.len(),
        states.len() - path.len(),
        p.diagonal().as_slice()
    );
    assert!(worst <= 0.0, "V non-increasing at every state: {worst}");
}

#[test]
fn the_interval_check_refuses_a_combination_that_is_not_definite() {
    // The check can fail: a single state's S_k = z f' + f z' has rank 2 and
    // one negative eigenvalue (unless f is parallel to z), never definite.
    let (z, f) = z_and_rate(&X0);
    let s = s_matrix(&z, &f);
    assert!(interval_cholesky_succeeds(&s).is_none());
}

#[test]
fn no_region_carries_the_regional_claim_because_the_blend_at_rest_is_off() {
    // At rest the rules' blend A_h(0) (R1 weighs 0.63; the others' q-rows carry
    // sqrt(1 - 3 * 0.56^2) = 0.24) differs from A(0) = A_1 (rule R1 sits at the
    // origin). Every region contains the origin, so every error bound is at
    // least ||A(0) - A_h(0)||; the robust conditions must hold for every
    // ||dA|| <= a, and a real rank-one dA of norm sigma_min(A_h(0) + B K)
    // makes the closed loop singular (an eigenvalue at 0): no P, no
    // multipliers satisfy them (continuous or sampled: at psi = [x; x; 0; 0; 0]
    // Lambda_1 contains 2 x' P (A_h + B K + dA) x) once a >= sigma_min.
    let model = crate::common::shipped("xu2020_regional.tsf");
    let r1 = &model.rules[0];
    assert_eq!(r1.at.as_deref(), Some(&[0.0; 6][..]), "R1 at the origin");
    let mut h = vec![0.0; model.rules.len()];
    assert!(tsfc::sim::adaptive::strengths(&model, &[0.0; 6], &mut h).expect("h"));
    let a_h = model
        .rules
        .iter()
        .zip(&h)
        .fold(DMatrix::zeros(6, 6), |s, (r, hi)| s + &r.a * *hi);
    let at_rest = (&r1.a - &a_h).singular_values().max();
    let j = DMatrix::from_fn(3, 3, |r, c| J[r][c]);
    let mut k = DMatrix::zeros(3, 6);
    k.view_mut((0, 0), (3, 3)).copy_from(&(&j * -KW));
    k.view_mut((0, 3), (3, 3)).copy_from(&(&j * -KQ));
    let closed = &a_h + &r1.b * &k;
    let radius = closed.singular_values().min();
    println!("xu at rest: ||A(0) - A_h(0)|| = {at_rest:.6}, sigma_min(A_h(0) + B K) = {radius:.6}, h(0) = {h:.4?}");
    assert!(at_rest > 1.2 * radius, "{at_rest} vs {radius}");
    // The true plant at rest is stable with the gain: the obstacle is the
    // unstructured bound of the blend's error, not the loop.
    let true_loop = &r1.a + &r1.b * &k;
    let eig = true_loop.complex_eigenvalues();
    assert!(eig.iter().all(|e| e.re < 0.0), "{eig:?}");
}
