//! Generates the PETSc/SLEPc bindings at build time.
//!
//! Finds the libraries through PETSC_DIR/PETSC_ARCH and SLEPC_DIR (a cluster's own build), else
//! through pkg-config (Debian's packages). Refuses a complex-scalar or single-precision PETSc
//! with a message that says what to install. Static-inline helpers (MatSetValue, ...) are made
//! reachable through a small C shim that bindgen writes and `cc` compiles.

use std::env;
use std::path::{Path, PathBuf};

fn fail(msg: &str) -> ! {
    eprintln!("\npetsc-sys: {msg}\n");
    panic!("petsc-sys: {msg}");
}

struct Found {
    include_dirs: Vec<PathBuf>,
}

fn from_dirs(petsc_dir: &Path) -> Found {
    let arch = env::var("PETSC_ARCH").unwrap_or_default();
    let mut include_dirs = vec![petsc_dir.join("include")];
    let mut lib_dirs = vec![petsc_dir.join("lib")];
    if !arch.is_empty() {
        include_dirs.push(petsc_dir.join(&arch).join("include"));
        lib_dirs.push(petsc_dir.join(&arch).join("lib"));
    }
    let slepc_dir = env::var("SLEPC_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|_| {
            fail("PETSC_DIR is set but SLEPC_DIR is not: set SLEPC_DIR to your SLEPc installation")
        });
    include_dirs.push(slepc_dir.join("include"));
    lib_dirs.push(slepc_dir.join("lib"));
    if !arch.is_empty() {
        include_dirs.push(slepc_dir.join(&arch).join("include"));
        lib_dirs.push(slepc_dir.join(&arch).join("lib"));
    }
    let find = |names: &[&'static str]| {
        for dir in &lib_dirs {
            for name in names {
                if dir.join(format!("lib{name}.so")).exists()
                    || dir.join(format!("lib{name}.a")).exists()
                {
                    println!("cargo:rustc-link-search=native={}", dir.display());
                    return Some(*name);
                }
            }
        }
        None
    };
    let petsc_lib = find(&["petsc_real", "petsc"]);
    let slepc_lib = find(&["slepc_real", "slepc"]);
    let petsc_lib = petsc_lib.unwrap_or_else(|| fail("no libpetsc under PETSC_DIR/PETSC_ARCH/lib"));
    let slepc_lib = slepc_lib.unwrap_or_else(|| fail("no libslepc under SLEPC_DIR/PETSC_ARCH/lib"));
    println!("cargo:rustc-link-lib={slepc_lib}");
    println!("cargo:rustc-link-lib={petsc_lib}");
    for dir in &lib_dirs {
        if dir.exists() {
            println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display());
        }
    }
    Found { include_dirs }
}

fn from_pkg_config() -> Found {
    let help = "PETSc/SLEPc not found. Run scripts/setup (Debian: libpetsc-real-dev \
                libslepc-real-dev), or set PETSC_DIR, PETSC_ARCH and SLEPC_DIR";
    let petsc = pkg_config::Config::new()
        .probe("PETSc")
        .unwrap_or_else(|e| fail(&format!("{help} ({e})")));
    let slepc = pkg_config::Config::new()
        .probe("SLEPc")
        .unwrap_or_else(|e| fail(&format!("{help} ({e})")));
    let mut include_dirs = petsc.include_paths;
    include_dirs.extend(slepc.include_paths);
    Found { include_dirs }
}

fn mpi_include_dirs() -> Vec<PathBuf> {
    for name in ["mpi", "ompi", "mpich"] {
        if let Ok(lib) = pkg_config::Config::new().cargo_metadata(false).probe(name) {
            return lib.include_paths;
        }
    }
    if let Ok(out) = std::process::Command::new("mpicc")
        .arg("--showme:incdirs")
        .output()
    {
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        return text.split_whitespace().map(PathBuf::from).collect();
    }
    fail("MPI headers not found: install libopenmpi-dev (scripts/setup) or put mpicc on PATH")
}

/// Reads petscconf.h and refuses configurations squeal does not support.
fn check_configuration(include_dirs: &[PathBuf]) {
    let conf = include_dirs
        .iter()
        .map(|d| d.join("petscconf.h"))
        .find(|p| p.exists())
        .unwrap_or_else(|| fail("petscconf.h not found in the PETSc include directories"));
    println!("cargo:rerun-if-changed={}", conf.display());
    let text = std::fs::read_to_string(&conf).unwrap();
    let defined = |name: &str| {
        text.lines().any(|l| {
            let mut w = l.split_whitespace();
            w.next() == Some("#define") && w.next() == Some(name)
        })
    };
    if defined("PETSC_USE_COMPLEX") {
        fail(&format!(
            "{} is a complex-scalar PETSc; squeal needs real scalars \
             (Debian: libpetsc-real-dev, or configure PETSc with --with-scalar-type=real)",
            conf.display()
        ));
    }
    if !defined("PETSC_USE_REAL_DOUBLE") {
        fail(&format!(
            "{} is not a double-precision PETSc; configure with --with-precision=double",
            conf.display()
        ));
    }
    if defined("PETSC_USE_64BIT_INDICES") {
        fail(&format!(
            "{} is a PETSc with 64-bit indices; squeal is built for 32-bit PetscInt \
             (Debian: libpetsc-real-dev, not libpetsc64-real-dev; or configure PETSc without \
             --with-64-bit-indices)",
            conf.display()
        ));
    }
    if !defined("PETSC_HAVE_MUMPS") {
        println!(
            "cargo:warning=this PETSc has no MUMPS: direct solves will fail at run time \
             (configure PETSc with --download-mumps --download-scalapack)"
        );
    }
}

fn main() {
    println!("cargo:rerun-if-changed=wrapper.h");
    println!("cargo:rerun-if-changed=build.rs");
    for var in ["PETSC_DIR", "PETSC_ARCH", "SLEPC_DIR"] {
        println!("cargo:rerun-if-env-changed={var}");
    }

    let found = match env::var("PETSC_DIR") {
        Ok(dir) if !dir.is_empty() => from_dirs(Path::new(&dir)),
        _ => from_pkg_config(),
    };
    // squeal calls LAPACK/BLAS directly for small dense problems (the library PETSc uses;
    // SQUEAL_LAPACK_LIBS overrides, e.g. "mkl_rt" on a cluster).
    println!("cargo:rerun-if-env-changed=SQUEAL_LAPACK_LIBS");
    let lapack = std::env::var("SQUEAL_LAPACK_LIBS").unwrap_or_else(|_| "lapack blas".into());
    for lib in lapack.split_whitespace() {
        println!("cargo:rustc-link-lib={lib}");
    }
    // MUMPS' single-precision library, beside the double-precision one PETSc links
    // (libmumps-dev).
    println!("cargo:rustc-link-lib=smumps");
    let mut include_dirs = found.include_dirs;
    include_dirs.extend(mpi_include_dirs());
    check_configuration(&include_dirs);

    let out = PathBuf::from(env::var("OUT_DIR").unwrap());
    // The header is read where it lies: a copy into OUT_DIR, newer than the build script's
    // own output, made every later cargo call see petsc-sys as stale and rebuild it and
    // everything above it (bindgen's callbacks track every header it reads).
    let header = PathBuf::from(env::var("CARGO_MANIFEST_DIR").unwrap()).join("wrapper.h");

    let prefixes = "(Petsc|Vec|Mat|KSP|PC|EPS|ST|BV|DS|RG|PEP|SVD|IS|Slepc|PETSC|SLEPC|MAT|VEC|NORM_|INSERT_|ADD_)";
    let shim = out.join("static_fns");
    let mut builder = bindgen::Builder::default()
        .header(header.to_str().unwrap())
        .allowlist_function(format!("{prefixes}.*"))
        .allowlist_type(format!("{prefixes}.*"))
        .allowlist_type("_p_.*")
        .allowlist_type("SMUMPS_STRUC_C")
        .allowlist_function("smumps_c")
        .allowlist_var(format!("{prefixes}.*"))
        // MPI types come from rsmpi's mpi-sys, so communicators pass straight through.
        .blocklist_type("MPI_.*")
        .blocklist_type("ompi_.*")
        .blocklist_type("mca_.*")
        .blocklist_type("opal_.*")
        // The header redefines these as macros; their static-inline shims do not compile.
        .blocklist_function("KSPDefaultConverged.*")
        .blocklist_function("KSPSkipConverged")
        .blocklist_function(".*_Private")
        .raw_line("#[allow(unused_imports)] use mpi_sys::*;")
        .default_enum_style(bindgen::EnumVariation::Consts)
        .prepend_enum_name(false)
        .layout_tests(false)
        .derive_debug(false)
        .wrap_static_fns(true)
        .wrap_static_fns_path(&shim)
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()));
    for dir in &include_dirs {
        builder = builder.clang_arg(format!("-I{}", dir.display()));
    }
    let bindings = builder
        .generate()
        .unwrap_or_else(|e| fail(&format!("bindgen failed: {e}")));
    bindings.write_to_file(out.join("bindings.rs")).unwrap();

    let mut cc = cc::Build::new();
    cc.file(shim.with_extension("c"))
        .include(&out)
        .include(env::current_dir().unwrap())
        .warnings(false);
    for dir in &include_dirs {
        cc.include(dir);
    }
    cc.compile("petsc_sys_static_fns");
}
