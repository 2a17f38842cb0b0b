//! Exports the BLAS routines that `la::one_column_gemm` defines, so that the libraries the
//! executable loads (MUMPS) reach them before the BLAS library's own: an executable's symbols
//! are not in the dynamic symbol table unless asked for. `-u` keeps their object in the link.

fn main() {
    for symbol in ["sgemm_", "dgemm_", "strsm_", "dtrsm_"] {
        println!("cargo:rustc-link-arg=-Wl,-u,{symbol}");
        println!("cargo:rustc-link-arg=-Wl,--export-dynamic-symbol={symbol}");
    }
    println!("cargo:rerun-if-changed=src/build.rs");
}
