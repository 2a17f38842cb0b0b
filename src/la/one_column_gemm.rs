//! Matrix products with one column sent to the matrix-vector product: `sgemm_` and `dgemm_`
//! defined here, ahead of the BLAS library in the process's symbol lookup (the executable
//! exports them: build.rs), so MUMPS' calls reach them.
//!
//! Why: MUMPS' forward and backward solves multiply each front's factor panel by the
//! right-hand sides with GEMM; with one right-hand side (every solve of the transient's Newton
//! iteration) that is a GEMM with n = 1. OpenBLAS before 0.3.28 (Debian ships 0.3.21) packs the
//! panel into a buffer before it multiplies, so the factor is read, written and read again
//! instead of streamed once: on the 600k brake's growth step its packing routines took 26 % of
//! the samples (benches/transient-results.md, eighteenth session). GEMV streams the panel once.
//!
//! Every other call goes on to the library's own GEMM (the next definition of the symbol:
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

extern "C" {
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

static FORWARDING: AtomicBool = AtomicBool::new(true);
static FORWARDED: AtomicU64 = AtomicU64::new(0);
static PASSED_ON: AtomicU64 = AtomicU64::new(0);

/// Sends GEMMs with one column (or one row) of the result to GEMV (`true`, the default), or
/// every GEMM to the library (`false`).
pub fn set_forwarding(on: bool) {
    FORWARDING.store(on, Ordering::Relaxed);
}

/// Calls of `sgemm_`/`dgemm_` this process has sent to GEMV, and passed on to the library's
/// GEMM, since it started. Zero forwarded calls after a MUMPS solve means the symbols were not
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

fn library_sgemm() -> Gemm<f32> {
    static F: OnceLock<usize> = OnceLock::new();
    let f = *F.get_or_init(|| next_definition(c"sgemm_") as usize);
    // SAFETY: the address of the library's sgemm_, whose signature is Gemm<f32>.
    unsafe { std::mem::transmute::<usize, Gemm<f32>>(f) }
}

fn library_dgemm() -> Gemm<f64> {
    static F: OnceLock<usize> = OnceLock::new();
    let f = *F.get_or_init(|| next_definition(c"dgemm_") as usize);
    // SAFETY: the address of the library's dgemm_, whose signature is Gemm<f64>.
    unsafe { std::mem::transmute::<usize, Gemm<f64>>(f) }
}

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
                let plan = if FORWARDING.load(Ordering::Relaxed) {
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

#[cfg(test)]
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
}
