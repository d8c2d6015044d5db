//! Helpers shared by the exported routines: option parsing, argument
//! validation and faer views over Fortran-style column-major buffers.

use core::ffi::{c_char, c_int};
use core::ptr::NonNull;
use std::panic::{catch_unwind, AssertUnwindSafe};

use faer::prelude::ReborrowMut;
use faer::{MatMut, MatRef};

/// Reads a character option and folds it to upper case.
///
/// # Safety
/// `c` must point to a readable `c_char`.
pub(crate) unsafe fn opt(c: *const c_char) -> u8 {
    (*c as u8).to_ascii_uppercase()
}

/// Which triangle of a symmetric matrix is referenced (`uplo`).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Uplo {
    Upper,
    Lower,
}

impl Uplo {
    /// Parses `'U'`/`'L'` (either case).
    pub(crate) fn parse(c: u8) -> Option<Self> {
        match c {
            b'U' => Some(Self::Upper),
            b'L' => Some(Self::Lower),
            _ => None,
        }
    }
}

/// Parses a BLAS `trans` option: `Some(false)` for `'N'`, `Some(true)` for
/// `'T'` or `'C'` (identical for real matrices).
pub(crate) fn parse_trans(c: u8) -> Option<bool> {
    match c {
        b'N' => Some(false),
        b'T' | b'C' => Some(true),
        _ => None,
    }
}

/// Returns the 1-based position attached to the first failed check, if any.
/// Each entry is `(argument_is_bad, position)`.
pub(crate) fn first_bad(checks: &[(bool, c_int)]) -> Option<c_int> {
    checks.iter().find(|(bad, _)| *bad).map(|&(_, pos)| pos)
}

/// Reports an illegal BLAS argument the way OpenBLAS does (message on
/// stderr, routine returns without touching its outputs).
pub(crate) fn blas_error(name: &str, pos: c_int) {
    eprintln!(" ** On entry to {name} parameter number {pos} had an illegal value");
}

/// `max(1, n)`, the minimum legal leading dimension for `n` rows.
pub(crate) fn ld_min(n: c_int) -> c_int {
    n.max(1)
}

/// Converts a validated, non-negative dimension.
pub(crate) fn dim(n: c_int) -> usize {
    usize::try_from(n).expect("dimension validated as non-negative")
}

/// Runs a LAPACK body, turning a panic inside faer into `info = internal`
/// instead of unwinding across the C ABI.
pub(crate) fn guarded(internal: c_int, body: impl FnOnce() -> c_int) -> c_int {
    catch_unwind(AssertUnwindSafe(body)).unwrap_or(internal)
}

/// Writes a workspace size into `work[0]` (as LAPACK does on queries and on
/// exit). Always at least 1.
///
/// # Safety
/// `work` must point to at least one writable `f64`.
pub(crate) unsafe fn set_work_size(work: *mut f64, size: usize) {
    *work = size.max(1) as f64;
}

fn non_null<T>(ptr: *const T, len: usize) -> *const T {
    if len == 0 || ptr.is_null() {
        NonNull::dangling().as_ptr()
    } else {
        ptr
    }
}

/// Read-only view of a column-major `rows x cols` matrix with leading
/// dimension `ld`.
///
/// # Safety
/// When `rows * cols > 0`, `ptr` must be valid for reads of
/// `ld * (cols - 1) + rows` elements for the lifetime `'a`, and `ld >= rows`.
pub(crate) unsafe fn mat_ref<'a>(
    ptr: *const f64,
    rows: usize,
    cols: usize,
    ld: usize,
) -> MatRef<'a, f64> {
    let ptr = non_null(ptr, rows * cols);
    MatRef::from_raw_parts(ptr, rows, cols, 1, ld as isize)
}

/// Mutable view of a column-major `rows x cols` matrix with leading
/// dimension `ld`.
///
/// # Safety
/// As [`mat_ref`], plus writes, and no other live reference may alias it.
pub(crate) unsafe fn mat_mut<'a>(
    ptr: *mut f64,
    rows: usize,
    cols: usize,
    ld: usize,
) -> MatMut<'a, f64> {
    let ptr = non_null(ptr, rows * cols) as *mut f64;
    MatMut::from_raw_parts_mut(ptr, rows, cols, 1, ld as isize)
}

/// First element and stride of a BLAS vector of `len` elements with
/// increment `inc != 0` (a negative increment walks the buffer backwards).
fn vec_start(ptr: *const f64, len: usize, inc: c_int) -> (*const f64, isize) {
    let inc = inc as isize;
    let ptr = non_null(ptr, len);
    if inc < 0 && len > 0 {
        // SAFETY of the offset is the caller's (the buffer spans it).
        (ptr.wrapping_offset((len as isize - 1) * -inc), inc)
    } else {
        (ptr, inc)
    }
}

/// Read-only `len x 1` view of a strided BLAS vector.
///
/// # Safety
/// `ptr` must be valid for reads of `1 + (len - 1) * |inc|` elements and
/// `inc != 0`.
pub(crate) unsafe fn vec_ref<'a>(ptr: *const f64, len: usize, inc: c_int) -> MatRef<'a, f64> {
    let (start, stride) = vec_start(ptr, len, inc);
    MatRef::from_raw_parts(start, len, 1, stride, 1)
}

/// Mutable `len x 1` view of a strided BLAS vector.
///
/// # Safety
/// As [`vec_ref`], plus writes, and no other live reference may alias it.
pub(crate) unsafe fn vec_mut<'a>(ptr: *mut f64, len: usize, inc: c_int) -> MatMut<'a, f64> {
    let (start, stride) = vec_start(ptr, len, inc);
    MatMut::from_raw_parts_mut(start as *mut f64, len, 1, stride, 1)
}

/// Part of a square matrix an operation touches.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Region {
    /// Every element.
    Full,
    /// One triangle, diagonal included.
    Triangle(Uplo),
}

impl Region {
    /// Row range of column `j` (of `rows` rows) inside the region.
    pub(crate) fn rows_of_col(self, j: usize, rows: usize) -> core::ops::Range<usize> {
        match self {
            Region::Full => 0..rows,
            Region::Triangle(Uplo::Upper) => 0..(j + 1).min(rows),
            Region::Triangle(Uplo::Lower) => j.min(rows)..rows,
        }
    }
}

/// `dst := beta * dst` over `region`; with `beta == 0` the old contents are
/// never read (NaN/Inf in `dst` are overwritten, as BLAS requires).
pub(crate) fn scale(mut dst: MatMut<'_, f64>, beta: f64, region: Region) {
    if beta == 1.0 {
        return;
    }
    let rows = dst.nrows();
    for j in 0..dst.ncols() {
        for i in region.rows_of_col(j, rows) {
            let x = dst.rb_mut().get_mut(i, j);
            *x = if beta == 0.0 { 0.0 } else { beta * *x };
        }
    }
}

/// Copies `src` into `dst` over `region` only (both of the same shape).
pub(crate) fn copy_region(mut dst: MatMut<'_, f64>, src: MatRef<'_, f64>, region: Region) {
    let rows = dst.nrows();
    for j in 0..dst.ncols() {
        for i in region.rows_of_col(j, rows) {
            *dst.rb_mut().get_mut(i, j) = *src.get(i, j);
        }
    }
}
