//! Shared test helpers: a seeded generator, padded column-major buffers and
//! naive reference operations.

#![allow(dead_code)]

use core::ffi::c_char;

/// Small seeded generator (64-bit LCG, high bits), uniform in [-1, 1).
pub struct Rng(u64);

impl Rng {
    /// Generator with the given seed.
    pub fn new(seed: u64) -> Self {
        Self(seed ^ 0x9E37_79B9_7F4A_7C15)
    }

    /// Next value in [-1, 1).
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// A character option as the FFI expects it.
pub fn ch(c: u8) -> c_char {
    c as c_char
}

/// Dense column-major matrix without padding (reference side).
#[derive(Clone, Debug, PartialEq)]
pub struct Dense {
    pub rows: usize,
    pub cols: usize,
    pub v: Vec<f64>,
}

impl Dense {
    /// Matrix from a generating function.
    pub fn from_fn(rows: usize, cols: usize, mut f: impl FnMut(usize, usize) -> f64) -> Self {
        let mut v = Vec::with_capacity(rows * cols);
        for j in 0..cols {
            for i in 0..rows {
                v.push(f(i, j));
            }
        }
        Self { rows, cols, v }
    }

    /// Random matrix.
    pub fn random(rows: usize, cols: usize, rng: &mut Rng) -> Self {
        Self::from_fn(rows, cols, |_, _| rng.next())
    }

    /// Random symmetric matrix.
    pub fn random_sym(n: usize, rng: &mut Rng) -> Self {
        let b = Self::random(n, n, rng);
        Self::from_fn(n, n, |i, j| b.at(i, j) + b.at(j, i))
    }

    /// Random symmetric positive definite matrix (B B^T + n I).
    pub fn random_spd(n: usize, rng: &mut Rng) -> Self {
        let b = Self::random(n, n, rng);
        let mut a = b.mul(&b.t());
        for i in 0..n {
            a.v[i + i * n] += n as f64;
        }
        a
    }

    /// Identity.
    pub fn eye(n: usize) -> Self {
        Self::from_fn(n, n, |i, j| if i == j { 1.0 } else { 0.0 })
    }

    /// Element (i, j).
    pub fn at(&self, i: usize, j: usize) -> f64 {
        self.v[i + j * self.rows]
    }

    /// Transpose.
    pub fn t(&self) -> Self {
        Self::from_fn(self.cols, self.rows, |i, j| self.at(j, i))
    }

    /// Naive triple-loop product.
    pub fn mul(&self, rhs: &Self) -> Self {
        assert_eq!(self.cols, rhs.rows);
        Self::from_fn(self.rows, rhs.cols, |i, j| {
            (0..self.cols).map(|l| self.at(i, l) * rhs.at(l, j)).sum()
        })
    }

    /// `self` with column j scaled by d[j].
    pub fn scale_cols(&self, d: &[f64]) -> Self {
        Self::from_fn(self.rows, self.cols, |i, j| self.at(i, j) * d[j])
    }

    /// Leading `cols` columns.
    pub fn left(&self, cols: usize) -> Self {
        Self::from_fn(self.rows, cols, |i, j| self.at(i, j))
    }

    /// Leading `rows` rows.
    pub fn top(&self, rows: usize) -> Self {
        Self::from_fn(rows, self.cols, |i, j| self.at(i, j))
    }

    /// max |self - other| over all elements.
    pub fn max_diff(&self, other: &Self) -> f64 {
        assert_eq!((self.rows, self.cols), (other.rows, other.cols));
        self.v
            .iter()
            .zip(&other.v)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    }

    /// max |a_ij|.
    pub fn max_abs(&self) -> f64 {
        self.v.iter().fold(0.0, |m, x| m.max(x.abs()))
    }

    /// max |self^T self - I|.
    pub fn orthogonality_error(&self) -> f64 {
        self.t().mul(self).max_diff(&Self::eye(self.cols))
    }
}

/// Column-major buffer with leading dimension `ld >= rows`; the padding
/// rows hold NaN so that reading them poisons results and writing them is
/// detectable.
#[derive(Clone, Debug)]
pub struct Padded {
    pub rows: usize,
    pub cols: usize,
    pub ld: usize,
    pub data: Vec<f64>,
}

impl Padded {
    /// Copy of `d` with `pad` extra rows of NaN per column.
    pub fn from_dense(d: &Dense, pad: usize) -> Self {
        let ld = (d.rows + pad).max(1);
        let mut data = vec![f64::NAN; ld * d.cols.max(1)];
        for j in 0..d.cols {
            for i in 0..d.rows {
                data[i + j * ld] = d.at(i, j);
            }
        }
        Self {
            rows: d.rows,
            cols: d.cols,
            ld,
            data,
        }
    }

    /// `rows x cols` buffer filled with `value` (padding NaN).
    pub fn filled(rows: usize, cols: usize, pad: usize, value: f64) -> Self {
        Self::from_dense(&Dense::from_fn(rows, cols, |_, _| value), pad)
    }

    /// Leading dimension as the FFI expects it.
    pub fn ld(&self) -> i32 {
        self.ld as i32
    }

    /// Element (i, j).
    pub fn at(&self, i: usize, j: usize) -> f64 {
        self.data[i + j * self.ld]
    }

    /// Sets element (i, j).
    pub fn set(&mut self, i: usize, j: usize, v: f64) {
        self.data[i + j * self.ld] = v;
    }

    /// The `rows x cols` contents.
    pub fn dense(&self) -> Dense {
        Dense::from_fn(self.rows, self.cols, |i, j| self.at(i, j))
    }

    /// Whether every padding element is still NaN.
    pub fn padding_intact(&self) -> bool {
        (0..self.cols).all(|j| (self.rows..self.ld).all(|i| self.at(i, j).is_nan()))
    }

    /// Fills the strict `uplo` triangle (`b'U'` or `b'L'`) with `value`.
    pub fn fill_strict_triangle(&mut self, uplo: u8, value: f64) {
        for j in 0..self.cols {
            for i in 0..self.rows {
                if (uplo == b'U' && i < j) || (uplo == b'L' && i > j) {
                    self.set(i, j, value);
                }
            }
        }
    }

    /// Whether the strict `uplo` triangle holds exactly `value` (NaN
    /// matches NaN).
    pub fn strict_triangle_is(&self, uplo: u8, value: f64) -> bool {
        let same = |x: f64| x == value || (x.is_nan() && value.is_nan());
        (0..self.cols).all(|j| {
            (0..self.rows)
                .filter(|&i| (uplo == b'U' && i < j) || (uplo == b'L' && i > j))
                .all(|i| same(self.at(i, j)))
        })
    }

    /// Symmetric matrix from the `uplo` triangle.
    pub fn sym_from(&self, uplo: u8) -> Dense {
        Dense::from_fn(self.rows, self.cols, |i, j| {
            let upper = i <= j;
            if (uplo == b'U') == upper || i == j {
                self.at(i, j)
            } else {
                self.at(j, i)
            }
        })
    }

    /// Pointer for read-only arguments.
    pub fn ptr(&self) -> *const f64 {
        self.data.as_ptr()
    }

    /// Pointer for in/out arguments.
    pub fn mut_ptr(&mut self) -> *mut f64 {
        self.data.as_mut_ptr()
    }
}

/// Records the worst error of a family of checks, asserts the tolerance and
/// prints the measurement (visible with `--nocapture`).
pub struct Worst {
    name: String,
    tol: f64,
    worst: f64,
}

impl Worst {
    /// New record for `name` with tolerance `tol`.
    pub fn new(name: impl Into<String>, tol: f64) -> Self {
        Self {
            name: name.into(),
            tol,
            worst: 0.0,
        }
    }

    /// Checks one error value (NaN fails).
    pub fn check(&mut self, err: f64, context: &str) {
        assert!(
            err <= self.tol,
            "{}: error {err:e} > {:e} ({context})",
            self.name,
            self.tol
        );
        self.worst = self.worst.max(err);
    }
}

impl Drop for Worst {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            eprintln!(
                "[accuracy] {}: worst {:.2e} (tolerance {:.0e})",
                self.name, self.worst, self.tol
            );
        }
    }
}
