//! Why no plant claim of the shipped Xu & Huang gains contains the paper's
//! x(0) (issue 34): a certificate of infeasibility, re-checked in interval
//! arithmetic (docs/language.md, "The plant claim", Xu & Huang).
//!
//! The loop: the spacecraft of specs/xu2020_regional.tsf (its declared plant,
//! A(x) x + B sat(u), which is the `dynamics` block: Euler's equation and the
//! quaternion kinematics), the shipped gain u = -J (0.36 w + 0.0648 q)
//! evaluated continuously, the actuator saturating at 2 N m. The states x_k:
//! the simulated trajectory of that loop from the paper's x(0) (RK4, 10 ms,
//! one state per second for 120 s). The question: is there P > 0 with
//! 2 x_k' P f(x_k) <= 0 for every k, i.e. a quadratic V = x' P x that does not
//! increase at any of those states? Clarabel finds multipliers lambda_k >= 0
//! with M = sum_k lambda_k (x_k f_k' + f_k x_k') positive definite; then for
//! every P > 0, sum_k lambda_k 2 x_k' P f_k = <P, M> > 0, so some k has
//! 2 x_k' P f_k > 0: no such P exists (Farkas' lemma for the cone of PSD
//! matrices). The test re-checks M > 0 with every f_k enclosed in interval
//! arithmetic with outward rounding (each f64 operation widened by one ulp)
//! and an interval Cholesky factorization of M.
//!
//! What it proves: no quadratic V (in x = [w; q], any P > 0) is non-increasing
//! at all of these states along the continuous saturated loop of the
//! declared plant with these gains. A certified set E(P, c) that contains
//! x(0) and is invariant, with V decreasing on it, contains the trajectory
//! from x(0), so no such certificate exists, to the accuracy of the
//! simulation that placed the states on the trajectory (the infeasibility
//! itself is exact for the listed states). What it does not prove: anything
//! about other gains, about non-quadratic functions (a fuzzy or
//! quaternion-based V), or about the sampled loop's looped functional, whose
//! V1 may rise between samples (its LMIs at psi = [x; x; 0; 0; 0] give the
//! continuous decrease of V1 only where the actuator is linear, which the
//! regional certificate requires anyway and x(0) violates: |u_s(x(0))| is
//! above 2 N m, checked below).

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
        std::array::from_fn(|r| {
            (0..3).fold(Iv::pt(0.0), |s, c| s.add(Iv::pt(J[r][c]).mul(v[c])))
        })
    };
    let cross = |a: &[Iv; 3], b: &[Iv; 3]| -> [Iv; 3] {
        std::array::from_fn(|r| {
            let (i, k) = ((r + 1) % 3, (r + 2) % 3);
            a[i].mul(b[k]).sub(a[k].mul(b[i]))
        })
    };
    let p = jv(&w);
    // u = -J (KW w + KQ q), saturated per axis.
    let inner: [Iv; 3] =
        std::array::from_fn(|r| Iv::pt(KW).mul(w[r]).add(Iv::pt(KQ).mul(q[r])));
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
            x = std::array::from_fn(|i| x[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
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

/// Multipliers lambda_k >= 0 with sum_k lambda_k S_k >= I, found by Clarabel
/// on the midpoints of the S_k (`None` when the SDP finds none).
fn multipliers(s: &[Vec<Vec<Iv>>]) -> Option<Vec<f64>> {
    let mut problem = Problem::new();
    let lambdas: Vec<_> = (0..s.len())
        .map(|k| problem.scalar(&format!("lambda{k}")).expect("var"))
        .collect();
    let mut sum = Expr::constant(&DMatrix::zeros(6, 6)).expect("zero");
    let mut total = Expr::constant(&DMatrix::zeros(1, 1)).expect("zero");
    for (k, (l, sk)) in lambdas.iter().zip(s).enumerate() {
        sum = sum.add(Expr::scaled(*l, &mid(sk)).expect("term")).expect("sum");
        total = total.add(Expr::var(*l)).expect("sum");
        problem
            .add_scalar(&format!("lambda{k} >= 0"), Expr::var(*l), Relation::Ge, 0.0)
            .expect("lambda >= 0");
    }
    let shifted = sum
        .sub(Expr::constant(&DMatrix::identity(6, 6)).expect("I"))
        .expect("M - I");
    problem.psd("M >= I", shifted, 0.0).expect("psd");
    problem.minimize(total).expect("objective");
    let sol = problem.solve(&SolveSettings::default()).expect("solver runs");
    let values = sol.assignment().ok()?;
    Some(
        lambdas
            .iter()
            .map(|l| values.value(*l).expect("value")[(0, 0)].max(0.0))
            .collect(),
    )
}

/// Whether every symmetric matrix in the interval matrix `m` is positive
/// definite: the interval Cholesky factorization succeeds with every pivot's
/// lower end positive (it encloses the factor of every member).
fn interval_cholesky_succeeds(m: &[Vec<Iv>]) -> Option<f64> {
    let n = m.len();
    let mut l = vec![vec![Iv::pt(0.0); n]; n];
    let mut smallest = f64::INFINITY;
    for j in 0..n {
        let mut d = m[j][j];
        for k in 0..j {
            d = d.sub(l[j][k].mul(l[j][k]));
        }
        if d.lo <= 0.0 {
            return None;
        }
        smallest = smallest.min(d.lo);
        let root = d.sqrt();
        l[j][j] = root;
        for i in j + 1..n {
            let mut s = m[i][j];
            for k in 0..j {
                s = s.sub(l[i][k].mul(l[j][k]));
            }
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
fn no_quadratic_v_decreases_along_the_xu_trajectory_from_the_paper_s_x0() {
    let states = trajectory(120);
    let s: Vec<_> = states
        .iter()
        .map(|x| {
            let (z, f) = z_and_rate(x);
            s_matrix(&z, &f)
        })
        .collect();
    let lambda = multipliers(&s).expect("Clarabel finds the multipliers");
    // M = sum lambda_k S_k in interval arithmetic (lambda_k exact as stored).
    let mut m = vec![vec![Iv::pt(0.0); 6]; 6];
    for (l, sk) in lambda.iter().zip(&s) {
        for r in 0..6 {
            for c in 0..6 {
                m[r][c] = m[r][c].add(Iv::pt(*l).mul(sk[r][c]));
            }
        }
    }
    let pivot = interval_cholesky_succeeds(&m);
    let used = lambda.iter().filter(|l| **l > 1e-9).count();
    println!(
        "xu infeasibility: {} states, {used} with lambda > 1e-9, smallest Cholesky pivot {pivot:?}",
        states.len()
    );
    assert!(pivot.is_some_and(|p| p > 0.0), "M is positive definite");
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
