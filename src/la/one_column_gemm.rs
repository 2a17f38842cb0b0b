//! Products and triangular solves with one column sent to the matrix-vector routines: `sgemm_`,
//! `dgemm_`, `strsm_` and `dtrsm_` defined here, ahead of the BLAS library in the process's
//! symbol lookup (the executable exports them: src/build.rs), so MUMPS' calls reach them.
//!
//! Why: MUMPS' forward and backward solves multiply each front's factor panel by the
//! right-hand sides with GEMM, and solve with its diagonal block with TRSM; with one
//! right-hand side (every solve of the transient's Newton iteration) those are calls with
//! n = 1. OpenBLAS before 0.3.28 (Debian ships 0.3.21) packs the panel into a buffer before it
//! multiplies, so the factor is read, written and read again instead of streamed once: on the
//! 600k brake's growth step its packing routines took 26 % of the samples, TRSM's another 3 %
//! (benches/transient-results.md). GEMV and TRSV stream the panel once.
//!
//! Every other call goes on to the library's own routine (the next definition of the symbol:
//! `dlsym(RTLD_NEXT)`). The forwarding can be switched off (`set_forwarding`) to measure it.

use std::ffi::CStr;
use std::os::raw::{c_char, c_int, c_void};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::OnceLock;

/// Fortran's hidden length of a CHARACTER argument (gfortran passes it after the others).
type FortranLen = usize;

type Gemm<T> = unsafe extern "C" fn(
    *const c_char,
    *const c_char,
    *const c_int,
    *const c_int,
    *const c_int,
    *const T,
    *const T,
    *const c_int,
    *const T,
    *const c_int,
    *const T,
    *mut T,
    *const c_int,
    FortranLen,
    FortranLen,
);

type Trsm<T> = unsafe extern "C" fn(
    *const c_char,
    *const c_char,
    *const c_char,
    *const c_char,
    *const c_int,
    *const c_int,
    *const T,
    *const T,
    *const c_int,
    *mut T,
    *const c_int,
    FortranLen,
    FortranLen,
    FortranLen,
    FortranLen,
);

extern "C" {
    fn strsv_(
        uplo: *const c_char,
        trans: *const c_char,
        diag: *const c_char,
        n: *const c_int,
        a: *const f32,
        lda: *const c_int,
        x: *mut f32,
        incx: *const c_int,
        uplo_len: FortranLen,
        trans_len: FortranLen,
        diag_len: FortranLen,
    );
    fn dtrsv_(
        uplo: *const c_char,
        trans: *const c_char,
        diag: *const c_char,
        n: *const c_int,
        a: *const f64,
        lda: *const c_int,
        x: *mut f64,
        incx: *const c_int,
        uplo_len: FortranLen,
        trans_len: FortranLen,
        diag_len: FortranLen,
    );
    fn sgemv_(
        trans: *const c_char,
        m: *const c_int,
        n: *const c_int,
        alpha: *const f32,
        a: *const f32,
        lda: *const c_int,
        x: *const f32,
        incx: *const c_int,
        beta: *const f32,
        y: *mut f32,
        incy: *const c_int,
        trans_len: FortranLen,
    );
    fn dgemv_(
        trans: *const c_char,
        m: *const c_int,
        n: *const c_int,
        alpha: *const f64,
        a: *const f64,
        lda: *const c_int,
        x: *const f64,
        incx: *const c_int,
        beta: *const f64,
        y: *mut f64,
        incy: *const c_int,
        trans_len: FortranLen,
    );
}

static FORWARDING_GEMM: AtomicBool = AtomicBool::new(true);
static FORWARDING_TRSM: AtomicBool = AtomicBool::new(true);
static FORWARDED: AtomicU64 = AtomicU64::new(0);
static PASSED_ON: AtomicU64 = AtomicU64::new(0);

/// Sends GEMMs and TRSMs with one column (or one row) of the result to GEMV and TRSV (`true`,
/// the default), or every call to the library (`false`).
pub fn set_forwarding(on: bool) {
    set_forwarding_of(on, on);
}

/// The forwarding of GEMM and of TRSM, separately (to measure each).
pub fn set_forwarding_of(gemm: bool, trsm: bool) {
    FORWARDING_GEMM.store(gemm, Ordering::Relaxed);
    FORWARDING_TRSM.store(trsm, Ordering::Relaxed);
}

/// Calls of the four routines this process has sent to GEMV or TRSV, and passed on to the
/// library's own, since it started. Zero forwarded calls after a MUMPS solve means the symbols were not
/// interposed (the executable does not export them).
pub fn calls() -> (u64, u64) {
    (
        FORWARDED.load(Ordering::Relaxed),
        PASSED_ON.load(Ordering::Relaxed),
    )
}

/// The library's own definition of `name` (the next one after this executable's).
fn next_definition(name: &CStr) -> *mut c_void {
    // SAFETY: dlsym with a NUL-terminated name; RTLD_NEXT searches the objects loaded after
    // this one, so it cannot return the definitions of this file.
    let f = unsafe { libc::dlsym(libc::RTLD_NEXT, name.as_ptr()) };
    if f.is_null() {
        // No BLAS after the executable: nothing to forward to, and no way to go on.
        eprintln!(
            "squeal: the BLAS library's {} is not loaded (the process links no BLAS)",
            name.to_string_lossy()
        );
        std::process::abort();
    }
    f
}

macro_rules! library {
    ($fn_name:ident, $symbol:literal, $signature:ty) => {
        fn $fn_name() -> $signature {
            static F: OnceLock<usize> = OnceLock::new();
            let f = *F.get_or_init(|| next_definition($symbol) as usize);
            // SAFETY: the address of the library's definition of the symbol, whose signature
            // is BLAS' (the type named here).
            unsafe { std::mem::transmute::<usize, $signature>(f) }
        }
    };
}

library!(library_sgemm, c"sgemm_", Gemm<f32>);
library!(library_dgemm, c"dgemm_", Gemm<f64>);
library!(library_strsm, c"strsm_", Trsm<f32>);
library!(library_dtrsm, c"dtrsm_", Trsm<f64>);

/// The GEMV that computes C = alpha op(A) op(B) + beta C when C has one column or one row.
struct AsGemv {
    trans: u8,
    /// Rows and columns of the matrix GEMV multiplies (as stored).
    rows: c_int,
    cols: c_int,
    /// Which operand is the matrix (true: A, false: B), and the vector's stride.
    matrix_is_a: bool,
    incx: c_int,
    incy: c_int,
}

fn transposed(t: u8) -> bool {
    matches!(t, b'T' | b't' | b'C' | b'c')
}

/// How GEMM (column-major, BLAS' conventions) maps onto one GEMV, if it does. `k = 0` stays a
/// GEMM: GEMV returns without scaling y by beta then, GEMM does not.
fn as_gemv(
    (ta, tb): (u8, u8),
    [m, n, k]: [c_int; 3],
    [lda, ldb, ldc]: [c_int; 3],
) -> Option<AsGemv> {
    if m <= 0 || n <= 0 || k <= 0 {
        return None;
    }
    if n == 1 {
        // c (m) = op(A) (m x k) x; x = op(B) (k x 1): B's column, or B's row (stride ldb).
        let (trans, rows, cols) = if transposed(ta) {
            (b'T', k, m)
        } else {
            (b'N', m, k)
        };
        let incx = if transposed(tb) { ldb } else { 1 };
        return Some(AsGemv {
            trans,
            rows,
            cols,
            matrix_is_a: true,
            incx,
            incy: 1,
        });
    }
    if m == 1 {
        // c^T (n) = op(B)^T (n x k) x; x = op(A)^T (k): A's row (stride lda), or A's column.
        let (trans, rows, cols) = if transposed(tb) {
            (b'N', n, k)
        } else {
            (b'T', k, n)
        };
        let incx = if transposed(ta) { 1 } else { lda };
        return Some(AsGemv {
            trans,
            rows,
            cols,
            matrix_is_a: false,
            incx,
            incy: ldc,
        });
    }
    None
}

macro_rules! one_column_gemm {
    ($name:ident, $t:ty, $gemv:ident, $library:ident) => {
        /// GEMM, with one column or one row of the result sent to GEMV (module doc).
        ///
        /// # Safety
        /// BLAS' contract: valid pointers to the operands their dimensions describe.
        #[no_mangle]
        #[allow(clippy::too_many_arguments)]
        pub unsafe extern "C" fn $name(
            transa: *const c_char,
            transb: *const c_char,
            m: *const c_int,
            n: *const c_int,
            k: *const c_int,
            alpha: *const $t,
            a: *const $t,
            lda: *const c_int,
            b: *const $t,
            ldb: *const c_int,
            beta: *const $t,
            c: *mut $t,
            ldc: *const c_int,
            transa_len: FortranLen,
            transb_len: FortranLen,
        ) {
            // SAFETY: the caller's (BLAS' contract); GEMV reads the same operands.
            unsafe {
                let plan = if FORWARDING_GEMM.load(Ordering::Relaxed) {
                    as_gemv(
                        (*transa as u8, *transb as u8),
                        [*m, *n, *k],
                        [*lda, *ldb, *ldc],
                    )
                } else {
                    None
                };
                match plan {
                    Some(g) => {
                        FORWARDED.fetch_add(1, Ordering::Relaxed);
                        let trans = g.trans as c_char;
                        let (matrix, ld, x) = if g.matrix_is_a {
                            (a, lda, b)
                        } else {
                            (b, ldb, a)
                        };
                        $gemv(
                            &trans, &g.rows, &g.cols, alpha, matrix, ld, x, &g.incx, beta, c,
                            &g.incy, 1,
                        );
                    }
                    None => {
                        PASSED_ON.fetch_add(1, Ordering::Relaxed);
                        $library()(
                            transa, transb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc,
                            transa_len, transb_len,
                        );
                    }
                }
            }
        }
    };
}

one_column_gemm!(sgemm_, f32, sgemv_, library_sgemm);
one_column_gemm!(dgemm_, f64, dgemv_, library_dgemm);

/// The TRSV that solves op(A) X = alpha B (side L) or X op(A) = alpha B (side R) when X has one
/// column (L) or one row (R): B scaled by alpha in place first.
struct AsTrsv {
    trans: u8,
    order: c_int,
    incx: c_int,
}

/// How TRSM maps onto one TRSV, if it does. alpha = 0 stays a TRSM (it only zeroes B).
fn as_trsv(side: u8, trans: u8, [m, n]: [c_int; 2], ldb: c_int) -> Option<AsTrsv> {
    if m <= 0 || n <= 0 {
        return None;
    }
    let left = matches!(side, b'L' | b'l');
    if left && n == 1 {
        let trans = if transposed(trans) { b'T' } else { b'N' };
        return Some(AsTrsv {
            trans,
            order: m,
            incx: 1,
        });
    }
    if !left && m == 1 {
        // x^T op(A) = alpha b^T is op(A)^T x = alpha b, x stored along B's row.
        let trans = if transposed(trans) { b'N' } else { b'T' };
        return Some(AsTrsv {
            trans,
            order: n,
            incx: ldb,
        });
    }
    None
}

macro_rules! one_column_trsm {
    ($name:ident, $t:ty, $trsv:ident, $library:ident) => {
        /// TRSM, with one column or one row of unknowns sent to TRSV (module doc).
        ///
        /// # Safety
        /// BLAS' contract: valid pointers to the operands their dimensions describe.
        #[no_mangle]
        #[allow(clippy::too_many_arguments)]
        pub unsafe extern "C" fn $name(
            side: *const c_char,
            uplo: *const c_char,
            transa: *const c_char,
            diag: *const c_char,
            m: *const c_int,
            n: *const c_int,
            alpha: *const $t,
            a: *const $t,
            lda: *const c_int,
            b: *mut $t,
            ldb: *const c_int,
            side_len: FortranLen,
            uplo_len: FortranLen,
            transa_len: FortranLen,
            diag_len: FortranLen,
        ) {
            // SAFETY: the caller's (BLAS' contract); TRSV reads and writes the same operands.
            unsafe {
                let plan = if FORWARDING_TRSM.load(Ordering::Relaxed) && *alpha != 0.0 {
                    as_trsv(*side as u8, *transa as u8, [*m, *n], *ldb)
                } else {
                    None
                };
                match plan {
                    Some(t) => {
                        FORWARDED.fetch_add(1, Ordering::Relaxed);
                        if *alpha != 1.0 {
                            for i in 0..t.order as usize {
                                *b.add(i * t.incx as usize) *= *alpha;
                            }
                        }
                        let trans = t.trans as c_char;
                        $trsv(uplo, &trans, diag, &t.order, a, lda, b, &t.incx, 1, 1, 1);
                    }
                    None => {
                        PASSED_ON.fetch_add(1, Ordering::Relaxed);
                        $library()(
                            side, uplo, transa, diag, m, n, alpha, a, lda, b, ldb, side_len,
                            uplo_len, transa_len, diag_len,
                        );
                    }
                }
            }
        }
    };
}

one_column_trsm!(strsm_, f32, strsv_, library_strsm);
one_column_trsm!(dtrsm_, f64, dtrsv_, library_dtrsm);

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    /// A reference product in f64 with BLAS' conventions (column-major, op = N or T).
    #[allow(clippy::too_many_arguments)]
    fn reference(
        ta: u8,
        tb: u8,
        m: usize,
        n: usize,
        k: usize,
        alpha: f64,
        a: &[f64],
        lda: usize,
        b: &[f64],
        ldb: usize,
        beta: f64,
        c: &mut [f64],
        ldc: usize,
    ) {
        let at = |i: usize, l: usize| {
            if transposed(ta) {
                a[l + i * lda]
            } else {
                a[i + l * lda]
            }
        };
        let bt = |l: usize, j: usize| {
            if transposed(tb) {
                b[j + l * ldb]
            } else {
                b[l + j * ldb]
            }
        };
        for j in 0..n {
            for i in 0..m {
                let s: f64 = (0..k).map(|l| at(i, l) * bt(l, j)).sum();
                c[i + j * ldc] = alpha * s + beta * c[i + j * ldc];
            }
        }
    }

    fn filled(len: usize, seed: u64) -> Vec<f64> {
        let mut x = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (0..len)
            .map(|_| {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((x >> 11) as f64 / (1u64 << 53) as f64) - 0.5
            })
            .collect()
    }

    /// Every shape GEMV takes (one column, one row, both; each operand transposed or not,
    /// leading dimensions larger than the rows), in both precisions, against a product written
    /// out in f64: within the rounding of a k-term sum in the precision.
    #[test]
    fn one_column_and_one_row_products_equal_the_product_written_out() {
        set_forwarding(true);
        let before = calls().0;
        let shapes = [(7, 1, 5), (1, 6, 4), (1, 1, 9), (33, 1, 17)];
        let mut checked = 0;
        for &(m, n, k) in &shapes {
            for &ta in b"NT" {
                for &tb in b"NT" {
                    let (ar, ac) = if transposed(ta) { (k, m) } else { (m, k) };
                    let (br, bc) = if transposed(tb) { (n, k) } else { (k, n) };
                    let (lda, ldb, ldc) = (ar + 2, br + 3, m + 1);
                    let a = filled(lda * ac, 1 + m as u64);
                    let b = filled(ldb * bc, 2 + n as u64);
                    let c0 = filled(ldc * n, 3 + k as u64);
                    let (alpha, beta) = (0.75, -1.25);
                    let mut want = c0.clone();
                    reference(
                        ta, tb, m, n, k, alpha, &a, lda, &b, ldb, beta, &mut want, ldc,
                    );
                    let dims = [m as c_int, n as c_int, k as c_int];
                    let lds = [lda as c_int, ldb as c_int, ldc as c_int];
                    let (ta_c, tb_c) = (ta as c_char, tb as c_char);

                    let mut got = c0.clone();
                    // SAFETY: operands sized by their dimensions and leading dimensions.
                    unsafe {
                        dgemm_(
                            &ta_c,
                            &tb_c,
                            &dims[0],
                            &dims[1],
                            &dims[2],
                            &alpha,
                            a.as_ptr(),
                            &lds[0],
                            b.as_ptr(),
                            &lds[1],
                            &beta,
                            got.as_mut_ptr(),
                            &lds[2],
                            1,
                            1,
                        )
                    };
                    let (af, bf) = (
                        a.iter().map(|&v| v as f32).collect::<Vec<_>>(),
                        b.iter().map(|&v| v as f32).collect::<Vec<_>>(),
                    );
                    let mut got_s: Vec<f32> = c0.iter().map(|&v| v as f32).collect();
                    let (alpha_s, beta_s) = (alpha as f32, beta as f32);
                    // SAFETY: as above.
                    unsafe {
                        sgemm_(
                            &ta_c,
                            &tb_c,
                            &dims[0],
                            &dims[1],
                            &dims[2],
                            &alpha_s,
                            af.as_ptr(),
                            &lds[0],
                            bf.as_ptr(),
                            &lds[1],
                            &beta_s,
                            got_s.as_mut_ptr(),
                            &lds[2],
                            1,
                            1,
                        )
                    };
                    for j in 0..n {
                        for i in 0..m {
                            let idx = i + j * ldc;
                            let scale = k as f64 + 2.0;
                            let e64 = (got[idx] - want[idx]).abs();
                            let e32 = (got_s[idx] as f64 - want[idx]).abs();
                            assert!(
                                e64 <= scale * f64::EPSILON,
                                "dgemm {} {} {m}x{n}x{k}: {} vs {}",
                                ta as char,
                                tb as char,
                                got[idx],
                                want[idx]
                            );
                            assert!(
                                e32 <= scale * f32::EPSILON as f64,
                                "sgemm {} {} {m}x{n}x{k}: {} vs {}",
                                ta as char,
                                tb as char,
                                got_s[idx],
                                want[idx]
                            );
                            checked += 1;
                        }
                        // Rows of C beyond m (ldc > m) are not C's: untouched.
                        assert_eq!(got[m + j * ldc], c0[m + j * ldc]);
                    }
                }
            }
        }
        assert!(checked > 0);
        assert!(
            calls().0 >= before + 2 * 4 * shapes.len() as u64,
            "the products were not sent to GEMV"
        );
    }

    /// Shapes GEMV does not take go on to the library's GEMM, whose result they must equal.
    #[test]
    fn other_shapes_go_on_to_the_library() {
        let (m, n, k) = (5usize, 3usize, 4usize);
        let a = filled(m * k, 7);
        let b = filled(k * n, 8);
        let mut want = vec![0.5; m * n];
        reference(b'N', b'N', m, n, k, 1.0, &a, m, &b, k, 2.0, &mut want, m);
        let mut got = vec![0.5; m * n];
        let dims = [m as c_int, n as c_int, k as c_int];
        let before = calls().1;
        // SAFETY: operands sized by their dimensions.
        unsafe {
            dgemm_(
                &(b'N' as c_char),
                &(b'N' as c_char),
                &dims[0],
                &dims[1],
                &dims[2],
                &1.0,
                a.as_ptr(),
                &dims[0],
                b.as_ptr(),
                &dims[2],
                &2.0,
                got.as_mut_ptr(),
                &dims[0],
                1,
                1,
            )
        };
        assert!(calls().1 > before);
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() <= 8.0 * f64::EPSILON, "{g} vs {w}");
        }
    }

    /// Triangular solves with one column (side L) or one row (side R) of unknowns, every
    /// uplo/trans/diag, alpha 1 and 0.5, leading dimensions larger than the order, in both
    /// precisions: B built from a known X by the product written out in f64, the solve must
    /// return X within the forward error bound of a triangular solve, c n u cond (A is
    /// diagonally dominant: diagonal in [1.5, 2.5], off-diagonal entries below 0.5 / n, so
    /// cond <= 3; c = 4). A unit diagonal is stored as 100 so that reading it would show.
    #[test]
    fn one_column_and_one_row_triangular_solves_return_the_known_solution() {
        set_forwarding(true);
        let before = calls().0;
        let order = 23usize;
        let mut cases = 0u64;
        for &side in b"LR" {
            for &uplo in b"UL" {
                for &trans in b"NT" {
                    for &diag in b"NU" {
                        for &alpha in &[1.0, 0.5] {
                            let lda = order + 2;
                            let noise = filled(lda * order, 11 + cases);
                            let a: Vec<f64> = (0..lda * order)
                                .map(|idx| {
                                    let (i, j) = (idx % lda, idx / lda);
                                    let inside =
                                        i < order && if uplo == b'U' { i <= j } else { i >= j };
                                    match (inside, i == j) {
                                        (false, _) => 1e30,
                                        (true, true) if diag == b'U' => 100.0,
                                        (true, true) => 2.0 + noise[idx],
                                        (true, false) => noise[idx] / order as f64,
                                    }
                                })
                                .collect();
                            let op = |i: usize, j: usize| {
                                let (r, c) = if trans == b'T' { (j, i) } else { (i, j) };
                                let inside = if uplo == b'U' { r <= c } else { r >= c };
                                match (inside, r == c) {
                                    (false, _) => 0.0,
                                    (true, true) if diag == b'U' => 1.0,
                                    (true, _) => a[r + c * lda],
                                }
                            };
                            let x = filled(order, 40 + cases);
                            // b = op(A) x / alpha (side L) or b^T = x^T op(A) / alpha (side R).
                            let b: Vec<f64> = (0..order)
                                .map(|i| {
                                    (0..order)
                                        .map(|l| {
                                            if side == b'L' {
                                                op(i, l) * x[l]
                                            } else {
                                                x[l] * op(l, i)
                                            }
                                        })
                                        .sum::<f64>()
                                        / alpha
                                })
                                .collect();
                            // B stored as a column (L, ldb = order + 1) or a row (R, ldb = 3).
                            let (m, n, ldb, stride) = if side == b'L' {
                                (order, 1, order + 1, 1)
                            } else {
                                (1, order, 3, 3)
                            };
                            let mut b64 = vec![7.0; ldb * n.max(1) + stride * order];
                            for i in 0..order {
                                b64[i * stride] = b[i];
                            }
                            let mut b32: Vec<f32> = b64.iter().map(|&v| v as f32).collect();
                            let a32: Vec<f32> = a.iter().map(|&v| v as f32).collect();
                            let flags = [side, uplo, trans, diag].map(|f| f as c_char);
                            let (mi, ni, ldai, ldbi) =
                                (m as c_int, n as c_int, lda as c_int, ldb as c_int);
                            let alpha32 = alpha as f32;
                            // SAFETY: operands sized by their dimensions and leading dimensions.
                            unsafe {
                                dtrsm_(
                                    &flags[0],
                                    &flags[1],
                                    &flags[2],
                                    &flags[3],
                                    &mi,
                                    &ni,
                                    &alpha,
                                    a.as_ptr(),
                                    &ldai,
                                    b64.as_mut_ptr(),
                                    &ldbi,
                                    1,
                                    1,
                                    1,
                                    1,
                                );
                                strsm_(
                                    &flags[0],
                                    &flags[1],
                                    &flags[2],
                                    &flags[3],
                                    &mi,
                                    &ni,
                                    &alpha32,
                                    a32.as_ptr(),
                                    &ldai,
                                    b32.as_mut_ptr(),
                                    &ldbi,
                                    1,
                                    1,
                                    1,
                                    1,
                                );
                            }
                            let x_max = crate::measure::largest_abs(x.iter());
                            for i in 0..order {
                                let bound = |u: f64| 4.0 * order as f64 * u * 3.0 * x_max;
                                let (e64, e32) = (
                                    (b64[i * stride] - x[i]).abs(),
                                    (b32[i * stride] as f64 - x[i]).abs(),
                                );
                                let case = format!(
                                    "{} {} {} {} alpha {alpha}, x[{i}] = {}",
                                    side as char, uplo as char, trans as char, diag as char, x[i]
                                );
                                assert!(
                                    e64 <= bound(f64::EPSILON),
                                    "dtrsm {case}: {}",
                                    b64[i * stride]
                                );
                                assert!(
                                    e32 <= bound(f32::EPSILON as f64),
                                    "strsm {case}: {}",
                                    b32[i * stride]
                                );
                            }
                            cases += 1;
                        }
                    }
                }
            }
        }
        assert_eq!(cases, 32);
        assert!(
            calls().0 >= before + 2 * cases,
            "the solves were not sent to TRSV"
        );
    }
}
