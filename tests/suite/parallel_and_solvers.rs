//! Parallel consistency and the solver routes of the la layer:
//!
//! - the same real modes on 1 and 2 ranks to round-off (DESIGN.md §4);
//! - the quadratic route (SLEPc PEP, real arithmetic) against the closed form of uncoupled
//!   damped oscillators, m s^2 + c s + k = 0: s = (-c +- sqrt(c^2 - 4 m k)) / (2 m), which
//!   come as conjugate pairs;
//! - the matrices model source on real data (brake M0, Graebner et al., ZAMM 2016): the modes
//!   below 3 kHz by spectrum slicing (Sylvester inertia) equal the 20 lowest by count;
//! - Matrix Market export then import gives the same operator.
//! - the transient's per-rank LU (PETSc's sequential LU on every rank, no pivoting) solves the
//!   Newmark Jacobian of brake M0 with friction (unsymmetric) backward stably, like MUMPS;
//!   MUMPS in single precision within the single-precision bound, refined in double
//!   precision to the double bound in at most 3 steps, and renewed in place on new values.
//! - values copied and added between matrices whose patterns nest (the static tangent's K0)
//!   land exactly where they belong, across the ranks' column split, and a factorization
//!   renewed afterwards factors the new values.
//! - the block of chosen rows and columns (a nonlinear elimination's operator) holds
//!   exactly the matrix's entries there, rows of other ranks included, on every rank.
//! - the local sparse LU (a nonlinear elimination's factor) solves a block of brake M0's
//!   Newmark Jacobian backward stably, like LAPACK's pivoted LU, and reports a zero pivot.
//! - dense blocks added through a plan of their entries' places (the contact tangent's
//!   route) land exactly where MatSetValues would put them, rows of other ranks included.
//! - the product with a matrix's chosen columns, stored by column on each rank's rows (a
//!   nonlinear elimination's change of the linear force), equals the whole product.

use super::TestResult;
use mpi::collective::{CommunicatorCollectives, SystemOperation};
use std::path::{Path, PathBuf};

use squeal::eigen::real_modes::{real_modes, RealModeRequest};
use squeal::fem::petsc::assemble_system;
use squeal::io::matrix_market;
use squeal::io::user_matrices::{load_sum, MatrixTerm};
use squeal::la::one_column_gemm;
use squeal::la::Preallocation;
use squeal::la::{
    solve_quadratic, BlockAddPlan, DirectSolver, Factorization, MatrixFormat, Petsc,
    QuadraticOptions, Selection, SparseMatrix, Vector,
};
use squeal::mesh::structured::block;
use squeal::mesh::Clamp;
use squeal::mesh::ElementKind;

use squeal::measure::{exceeds, nan_max, nan_min};

use super::common::{check_le, one_rank_rows, rel, say, solve_modes, steel, suite_dir};

/// max |x - 1| where `solver` solves x from b = `m` 1.
fn error_solving_for_ones(solver: &DirectSolver, m: &SparseMatrix) -> TestResult<f64> {
    let mut ones = m.new_vector()?;
    ones.set_all(1.0)?;
    let mut rhs = ones.duplicate()?;
    m.mult(&ones, &mut rhs)?;
    let mut x = ones.duplicate()?;
    solver.solve(&rhs, &mut x)?;
    x.axpy(-1.0, &ones)?;
    Ok(x.norm_inf()?)
}

/// Rank r's blocks for the plan test: (global id, indices); one holds a -1 (skipped).
fn rank_blocks(r: usize, n: usize) -> Vec<(usize, Vec<i32>)> {
    let mut blocks: Vec<(usize, Vec<i32>)> = (0..5)
        .map(|t| {
            let id = 5 * r + t;
            let k = ((id * 13) % (n - 2)) as i32;
            (id, vec![k, k + 1, k + 2])
        })
        .collect();
    let k = ((r * 11) % (n - 1)) as i32;
    blocks.push((100 + r, vec![k, -1, k + 1]));
    blocks
}

/// Entry (a, c) of block `id`: quarters of small integers, so every sum is exact in any
/// order.
fn block_value(id: usize, a: usize, c: usize) -> f64 {
    0.25 * (id + 1) as f64 + a as f64 + 0.5 * c as f64
}

/// `BlockAddPlan` (src/la/block_add.rs) adds every rank's dense blocks, which reach rows of
/// other ranks, into a pentadiagonal matrix: each entry must be exactly the sum of the
/// blocks' values there (computed here from every rank's list: the closed form), twice that
/// after a second addition with the same plan; entries outside the blocks stay as they were.
/// A block outside the pattern gives no plan on any rank; another list of blocks is refused
/// on every rank; a factor renewed after an addition solves with the new values.
fn planned_block_addition_lands_exactly_where_matsetvalues_would(petsc: &Petsc) -> TestResult {
    let n = 40;
    let (size, rank) = (petsc.size() as usize, petsc.rank() as usize);
    let local = rank * n / size..(rank + 1) * n / size;
    let base = |i: usize, j: usize| if i == j { 400.0 } else { 0.0 };
    let mut a = banded(petsc, n, local.clone(), 2, base)?;
    let mine = rank_blocks(rank, n);
    let indices: Vec<&[i32]> = mine.iter().map(|(_, b)| b.as_slice()).collect();
    let mut plan =
        BlockAddPlan::new(&a, &indices)?.ok_or("no plan for blocks inside the pattern")?;
    let mut sum = vec![0.0; n * n];
    for r in 0..size {
        for (id, b) in rank_blocks(r, n) {
            for (x, &i) in b.iter().enumerate() {
                for (y, &j) in b.iter().enumerate() {
                    if i >= 0 && j >= 0 {
                        sum[i as usize * n + j as usize] += block_value(id, x, y);
                    }
                }
            }
        }
    }
    let fill = |k: usize, dense: &mut [f64]| {
        let (id, b) = &mine[k];
        for x in 0..b.len() {
            for y in 0..b.len() {
                dense[x * b.len() + y] = block_value(*id, x, y);
            }
        }
    };
    plan.add(&mut a, &indices, fill)?;
    let once = entry_error(&a, |i, j| base(i, j) + sum[i * n + j])?;
    let mut solver = DirectSolver::factorize(petsc, &a, Factorization::Lu, "plan_")?;
    plan.add(&mut a, &indices, fill)?;
    let twice = entry_error(&a, |i, j| base(i, j) + 2.0 * sum[i * n + j])?;
    solver.refactorize(&a)?;
    let solve_error = error_solving_for_ones(&solver, &a)?;
    let outside: Vec<i32> = vec![0, 5];
    let no_plan = BlockAddPlan::new(&a, &[outside.as_slice()])?.is_none();
    let fewer = &indices[..indices.len() - 1];
    let refused = plan.add(&mut a, fewer, |_, _| {}).is_err();
    say(
        petsc,
        &format!("after one addition {once:.1e}, after two {twice:.1e}, solve after the renewed factor {solve_error:.1e}, block outside the pattern unplanned: {no_plan}, other blocks refused: {refused}"),
    );
    check_le("entries after one addition", once, 0.0)?;
    check_le("entries after two additions", twice, 0.0)?;
    // A = 400 I + blocks of entries below 10 (at most ~9 blocks per row): diagonally
    // dominant, condition number below 10.
    check_le("solution error with the renewed factor", solve_error, 1e-12)?;
    match (no_plan, refused) {
        (true, true) => Ok(()),
        (false, _) => Err("a block outside the pattern was planned".into()),
        (_, false) => Err("a plan was used for another list of blocks".into()),
    }
}

pub fn tests() -> Vec<super::NamedTest> {
    vec![
        ("same_modes_one_and_two_ranks", same_modes_one_and_two_ranks),
        (
            "quadratic_damped_oscillators_conjugate_pairs",
            quadratic_damped_oscillators_conjugate_pairs,
        ),
        (
            "brake_m0_modes_by_slicing_equal_modes_by_count",
            brake_m0_modes_by_slicing_equal_modes_by_count,
        ),
        (
            "matrix_market_export_import_roundtrip",
            matrix_market_export_import_roundtrip,
        ),
        (
            "brake_m0_newmark_jacobian_per_rank_lu_backward_stable",
            brake_m0_newmark_jacobian_per_rank_lu_backward_stable,
        ),
        (
            "brake_m0_newmark_jacobian_single_precision_mumps",
            brake_m0_newmark_jacobian_single_precision_mumps,
        ),
        (
            "brake_m0_single_precision_factor_renewed_in_place",
            brake_m0_single_precision_factor_renewed_in_place,
        ),
        (
            "nested_pattern_copy_and_axpy_set_exact_entries_and_a_refactorization_sees_them",
            nested_pattern_copy_and_axpy_set_exact_entries_and_a_refactorization_sees_them,
        ),
        (
            "planned_block_addition_lands_exactly_where_matsetvalues_would",
            planned_block_addition_lands_exactly_where_matsetvalues_would,
        ),
        (
            "block_holds_the_entries_of_its_rows_and_columns",
            block_holds_the_entries_of_its_rows_and_columns,
        ),
        (
            "brake_m0_newmark_block_local_sparse_lu_backward_stable",
            brake_m0_newmark_block_local_sparse_lu_backward_stable,
        ),
        (
            "selection_gathers_the_chosen_entries_in_their_order_on_every_rank",
            selection_gathers_the_chosen_entries_in_their_order_on_every_rank,
        ),
        (
            "brake_m0_column_block_product_equals_the_whole_product",
            brake_m0_column_block_product_equals_the_whole_product,
        ),
    ]
}

/// Brake M0's Newmark Jacobian with friction (unsymmetric; Graebner et al., ZAMM 2016): its
/// columns 1,500-2,699 taken by `ColumnBlock` on each rank's rows, times an x that is
/// nonzero on every third of them (a nonlinear elimination's move), equal J x by PETSc's
/// product on every row, rows of other ranks' columns included, to the round-off of two sums
/// of the same terms in another order: |difference| <= 2 n_row eps (|J| |x|)_i with n_row the
/// longest row's entries (the standard bound on a sum's rounding, for each of the two).
/// The entries stored over the ranks are those of the chosen columns, none lost or doubled.
fn brake_m0_column_block_product_equals_the_whole_product(petsc: &Petsc) -> TestResult {
    use squeal::la::ColumnBlock;
    let (j, _) = m0_newmark_system(petsc)?;
    let columns: Vec<usize> = (1500..2700.min(j.global_rows())).collect();
    let block = ColumnBlock::new(&j, &columns)?;
    let moved: Vec<(usize, f64)> = (0..columns.len())
        .step_by(3)
        .map(|p| (p, (0.37 * p as f64).sin() * (1.0 + (p % 7) as f64)))
        .collect();
    let own = j.ownership();
    let mut x_global = vec![0.0; j.global_rows()];
    for &(p, v) in &moved {
        x_global[columns[p]] = v;
    }
    let mut x = j.new_vector()?;
    x.local_mut()?.copy_from_slice(&x_global[own.clone()]);
    let mut whole = x.duplicate()?;
    j.mult(&x, &mut whole)?;
    // (|J| |x|)_i, the longest row and the entries in the chosen columns, on this rank's rows.
    let (mut scale, mut longest, mut stored) = (Vec::new(), 0usize, 0usize);
    j.for_each_local_row(|_, cols, vals| {
        longest = longest.max(cols.len());
        stored += cols
            .iter()
            .filter(|&&c| (1500..2700).contains(&(c as usize)))
            .count();
        scale.push(
            cols.iter()
                .zip(vals)
                .map(|(&c, v)| (v * x_global[c as usize]).abs())
                .sum::<f64>(),
        );
    })?;
    let mut by_columns = vec![0.0; own.len()];
    block.mult_add(1.0, moved.iter().copied(), &mut by_columns);
    let longest = squeal::parallel::max(petsc.world(), longest as f64);
    let allowed = 2.0 * longest * f64::EPSILON;
    let mut worst = 0.0f64;
    {
        let w = whole.local()?;
        for i in 0..own.len() {
            let ratio = if by_columns[i] == w[i] {
                0.0
            } else {
                (by_columns[i] - w[i]).abs() / nan_max(allowed * scale[i], f64::MIN_POSITIVE)
            };
            worst = nan_max(worst, ratio);
        }
    }
    let mut counts = vec![0.0; 2];
    counts[0] = block.entries() as f64;
    counts[1] = stored as f64;
    squeal::parallel::sum_in_place(petsc.world(), &mut counts);
    let mut worst_all = vec![worst];
    squeal::parallel::max_in_place(petsc.world(), &mut worst_all);
    say(
        petsc,
        &format!(
            "column block: {} entries over the ranks ({} in J's chosen columns), worst difference {:.2} of the round-off bound",
            counts[0], counts[1], worst_all[0]
        ),
    );
    if counts[0] != counts[1] {
        return Err(format!(
            "the column block holds {} entries, J has {} in those columns",
            counts[0], counts[1]
        )
        .into());
    }
    check_le("column block product / round-off bound", worst_all[0], 1.0)
}

/// A `Selection` built once gathers the same chosen entries (owned by any rank, in any
/// order) on every rank, each time, from vectors of the template's layout.
fn selection_gathers_the_chosen_entries_in_their_order_on_every_rank(petsc: &Petsc) -> TestResult {
    let (rank, size) = (petsc.rank() as usize, petsc.size() as usize);
    let global = 101;
    // Uneven ownership: the last rank holds the remainder.
    let share = global / size;
    let local = if rank + 1 == size {
        global - share * (size - 1)
    } else {
        share
    };
    let start = share * rank;
    let values = |scale: f64| -> Vec<f64> {
        (start..start + local)
            .map(|i| scale * (i as f64 + 0.5))
            .collect()
    };
    let x = Vector::from_local(petsc, &values(1.0))?;
    let y = Vector::from_local(petsc, &values(-2.0))?;
    let chosen = [100, 3, 57, 0, 42, 99];
    let selection = Selection::new(&x, &chosen)?;
    for (v, scale) in [(&x, 1.0), (&y, -2.0), (&x, 1.0)] {
        let got = selection.gather(v)?;
        let want: Vec<f64> = chosen.iter().map(|&i| scale * (i as f64 + 0.5)).collect();
        if got != want {
            return Err(format!("gathered {got:?}, expected {want:?}").into());
        }
    }
    Ok(())
}

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/brake-m0")
}

/// Modes of a rectangular cantilever (no doublets, so shapes are unique up to sign) on this
/// run's ranks, gathered in global DOF order; the 1-rank run stores them, the 2-rank run
/// compares against them.
fn same_modes_one_and_two_ranks(petsc: &Petsc) -> TestResult {
    let mesh = block([1.0, 0.12, 0.07], [12, 3, 2], ElementKind::Hex20, steel());
    let request = RealModeRequest {
        count: 8,
        tolerance: 1e-12,
        ..Default::default()
    };
    let (system, modes) = solve_modes(petsc, &mesh, &[Clamp::all("u0")], &request)?;
    let norm_k = system.stiffness.norm_infinity()?;
    let norm_m = system.mass.norm_infinity()?;
    // Per mode: frequency, backward error, condition number, then the shape.
    let mut rows = Vec::new();
    for ((f, shape), eta) in modes
        .frequencies_hz
        .iter()
        .zip(&modes.shapes)
        .zip(&modes.backward_errors)
    {
        // A shape's sign is arbitrary: it is aligned with the 1-rank one below.
        let v = shape.gather_all()?;
        let lambda = (2.0 * std::f64::consts::PI * f).powi(2);
        let x2: f64 = v.iter().map(|x| x * x).sum();
        let condition = (norm_k + lambda * norm_m) * x2 / lambda;
        rows.push(
            [*f, *eta, condition]
                .into_iter()
                .chain(v)
                .collect::<Vec<f64>>(),
        );
    }
    let Some(one) = one_rank_rows(petsc, "modes", &rows)? else {
        return Ok(());
    };
    // The round-off bound (first-order perturbation of a simple eigenvalue of a symmetric
    // definite pencil; Higham & Higham, "Structured backward error and condition of
    // generalized eigenvalue problems", SIMAX 20, 1998): an eigenpair with backward error eta
    // is exact for a pencil within eta of (K, M), so its eigenvalue lambda = omega^2 moves by at
    // most kappa eta relative, kappa = (||K|| + lambda ||M||) ||x||^2 / (lambda x^T M x) (here
    // x^T M x = 1). Two runs then differ in lambda by kappa (eta_1 + eta_2), in frequency by
    // half that. A shape moves by that over its relative gap to the nearest eigenvalue
    // (Davis-Kahan); both doubled for the first-order terms dropped.
    let lambdas: Vec<f64> = rows
        .iter()
        .map(|r| (2.0 * std::f64::consts::PI * r[0]).powi(2))
        .collect();
    let (mut df, mut dv, mut f_bound, mut v_bound) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (i, (here, there)) in rows.iter().zip(&one).enumerate() {
        let moved = here[2] * (here[1] + there[1]);
        let gap = lambdas
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != i)
            .map(|(_, l)| (l - lambdas[i]).abs() / lambdas[i])
            .fold(f64::INFINITY, nan_min);
        f_bound = nan_max(f_bound, moved);
        v_bound = nan_max(v_bound, 2.0 * moved / gap);
        df = nan_max(df, rel(here[0], there[0]));
        let (a, b) = (&there[3..], &here[3..]);
        let sign = if a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>() < 0.0 {
            -1.0
        } else {
            1.0
        };
        let norm = |v: &mut dyn Iterator<Item = f64>| v.map(|x| x * x).sum::<f64>().sqrt();
        dv = nan_max(
            dv,
            norm(&mut a.iter().zip(b).map(|(x, y)| x - sign * y)) / norm(&mut a.iter().copied()),
        );
    }
    say(
        petsc,
        &format!(
            "{} ranks vs 1: max rel. frequency difference {df:.1e} (round-off bound {f_bound:.1e}), max relative shape difference (2-norm) {dv:.1e} (bound {v_bound:.1e})",
            petsc.size()
        ),
    );
    check_le("relative frequency difference", df, f_bound)?;
    check_le("relative shape difference", dv, v_bound)
}

fn diagonal<'p>(
    petsc: &'p Petsc,
    local: std::ops::Range<usize>,
    value: impl Fn(usize) -> f64,
) -> TestResult<SparseMatrix<'p>> {
    let n = local.len();
    let p = Preallocation {
        diag: vec![1; n],
        off: vec![0; n],
        diag_upper: vec![1; n],
        off_upper: vec![0; n],
    };
    let mut a = SparseMatrix::new(petsc, MatrixFormat::Aij, 1, n, &p)?;
    for i in local {
        a.add_values(&[i as i32], &[i as i32], &[value(i)])?;
    }
    a.assemble()?;
    Ok(a)
}

fn quadratic_damped_oscillators_conjugate_pairs(petsc: &Petsc) -> TestResult {
    let n = 40;
    let (size, rank) = (petsc.size() as usize, petsc.rank() as usize);
    let local = rank * n / size..(rank + 1) * n / size;
    let m = |i: usize| 1.0 + 0.1 * i as f64;
    let c = |i: usize| 0.05 * (1.0 + i as f64);
    let k = |i: usize| (10.0 + i as f64).powi(2);
    let (mm, cc, kk) = (
        diagonal(petsc, local.clone(), m)?,
        diagonal(petsc, local.clone(), c)?,
        diagonal(petsc, local, k)?,
    );
    let opts = QuadraticOptions {
        count: 10,
        tolerance: 1e-12,
        ..Default::default()
    };
    let sol = solve_quadratic(petsc, &kk, &cc, &mm, &opts)?;
    let exact: Vec<(f64, f64)> = (0..n)
        .flat_map(|i| {
            let re = -c(i) / (2.0 * m(i));
            let im = (4.0 * m(i) * k(i) - c(i) * c(i)).sqrt() / (2.0 * m(i));
            [(re, im), (re, -im)]
        })
        .collect();
    let mut worst = 0.0f64;
    for &(re, im) in &sol.values {
        let d = exact
            .iter()
            .map(|&(er, ei)| {
                ((re - er).powi(2) + (im - ei).powi(2)).sqrt() / (er * er + ei * ei).sqrt()
            })
            .fold(f64::INFINITY, nan_min);
        worst = nan_max(worst, d);
        // The conjugate must be there too.
        if !sol.values.iter().any(|&(r2, i2)| {
            let tolerance = 1e-9 * nan_max(im.abs(), 1.0);
            (r2 - re).abs() < tolerance && (i2 + im).abs() < tolerance
        }) {
            return Err(format!("eigenvalue {re} + {im}i has no conjugate in the result").into());
        }
    }
    let smallest = exact
        .iter()
        .map(|&(r, i)| (r * r + i * i).sqrt())
        .fold(f64::INFINITY, nan_min);
    say(
        petsc,
        &format!(
            "{} eigenvalues, worst rel. error {worst:.1e}, max backward error {:.1e}",
            sol.values.len(),
            sol.backward_errors
                .iter()
                .fold(0.0f64, |a, &b| nan_max(a, b))
        ),
    );
    if exceeds(worst, 1e-9) {
        return Err(format!("worst relative eigenvalue error {worst:e}").into());
    }
    let nearest = sol
        .values
        .iter()
        .map(|&(r, i)| (r * r + i * i).sqrt())
        .fold(f64::INFINITY, nan_min);
    if exceeds(rel(nearest, smallest), 1e-9) {
        return Err(format!("smallest |s| found {nearest}, exact {smallest}").into());
    }
    Ok(())
}

fn brake_m0_modes_by_slicing_equal_modes_by_count(petsc: &Petsc) -> TestResult {
    let term = |f: &str| {
        vec![MatrixTerm {
            file: PathBuf::from(f),
            coefficient: 1.0,
            speed_power: 0,
        }]
    };
    let k = load_sum(petsc, &term("K1.mtx.gz"), &data_dir())?;
    let m = load_sum(petsc, &term("M.mtx.gz"), &data_dir())?;
    if k.rows != 4669 || exceeds(k.asymmetry, 1e-12) || exceeds(m.asymmetry, 1e-12) {
        return Err(format!(
            "M0: {} rows, asymmetry K {:e} M {:e}",
            k.rows, k.asymmetry, m.asymmetry
        )
        .into());
    }
    let by_count = real_modes(
        petsc,
        &k.matrix,
        &m.matrix,
        false,
        &RealModeRequest {
            count: 20,
            tolerance: 1e-12,
            ..Default::default()
        },
        "count_",
    )?;
    let f_max = 3000.0;
    let by_slicing = real_modes(
        petsc,
        &k.matrix,
        &m.matrix,
        false,
        &RealModeRequest {
            f_max_hz: Some(f_max),
            tolerance: 1e-12,
            ..Default::default()
        },
        "slice_",
    )?;
    let expected: Vec<f64> = by_count
        .frequencies_hz
        .iter()
        .copied()
        .filter(|&f| f < f_max)
        .collect();
    say(
        petsc,
        &format!(
            "M0: {} modes below {f_max} Hz by slicing, {} by count; first {:.4} Hz",
            by_slicing.frequencies_hz.len(),
            expected.len(),
            expected[0]
        ),
    );
    if by_slicing.frequencies_hz.len() != expected.len() {
        return Err(format!(
            "slicing found {:?}, count-based {:?}",
            by_slicing.frequencies_hz, expected
        )
        .into());
    }
    for (a, b) in by_slicing.frequencies_hz.iter().zip(&expected) {
        if exceeds(rel(*a, *b), 1e-9) {
            return Err(format!("frequency {a} (slicing) vs {b} (count)").into());
        }
    }
    let worst = by_count
        .backward_errors
        .iter()
        .fold(0.0f64, |a, &b| nan_max(a, b));
    if exceeds(worst, 1e-10) {
        return Err(format!("backward error {worst:e}").into());
    }
    Ok(())
}

fn matrix_market_export_import_roundtrip(petsc: &Petsc) -> TestResult {
    let mesh = block([0.3, 0.1, 0.05], [6, 2, 2], ElementKind::Hex20, steel());
    let system = assemble_system(petsc, &mesh, &[Clamp::all("u0")])?;
    let dir = suite_dir().join(format!("roundtrip-{}", petsc.size()));
    // Rank 0 makes the folder; its failure is shared before anyone waits for it.
    let made = petsc.rank() != 0 || std::fs::create_dir_all(&dir).is_ok();
    if squeal::parallel::any_rank(petsc.world(), !made) {
        return Err(format!("cannot create {}", dir.display()).into());
    }
    let path = dir.join("K.mtx");
    matrix_market::write(petsc.world(), &system.stiffness, &path)?;
    squeal::parallel::barrier(petsc.world());
    let back = load_sum(
        petsc,
        &[MatrixTerm {
            file: path.clone(),
            coefficient: 1.0,
            speed_power: 0,
        }],
        Path::new(""),
    )?;
    // Compare K x for a deterministic x; layouts may differ, so compare gathered products.
    let n = system.stiffness.global_rows();
    let mut x1 = system.stiffness.new_vector()?;
    let mut x2 = back.matrix.new_vector()?;
    let (r1, r2) = (x1.ownership(), x2.ownership());
    for (x, range) in [(&mut x1, r1), (&mut x2, r2)] {
        let mut l = x.local_mut()?;
        for (i, v) in range.clone().zip(l.iter_mut()) {
            *v = ((i * 7919) % 101) as f64 / 101.0 - 0.5;
        }
    }
    let (mut y1, mut y2) = (x1.duplicate()?, x2.duplicate()?);
    system.stiffness.mult(&x1, &mut y1)?;
    back.matrix.mult(&x2, &mut y2)?;
    let (a, b) = (y1.gather_all()?, y2.gather_all()?);
    let scale = a.iter().fold(0.0f64, |m, v| nan_max(m, v.abs()));
    let diff = a
        .iter()
        .zip(&b)
        .fold(0.0f64, |m, (p, q)| nan_max(m, (p - q).abs()))
        / scale;
    say(
        petsc,
        &format!(
            "K ({n} DOF) -> {} -> K: max rel. difference of K x {diff:.1e}",
            path.file_name().unwrap().to_string_lossy()
        ),
    );
    if back.rows != n || exceeds(back.asymmetry, 1e-15) || exceeds(diff, 1e-15) {
        return Err(format!(
            "rows {} vs {n}, asymmetry {:e}, difference {diff:e}",
            back.rows, back.asymmetry
        )
        .into());
    }
    Ok(())
}

/// The brake M0 Newmark Jacobian (see the test below) and b = J x_true for an x_true with
/// entries of both signs and several magnitudes.
fn m0_newmark_system<'p>(petsc: &'p Petsc) -> TestResult<(SparseMatrix<'p>, Vector<'p>)> {
    m0_newmark_system_with_friction(petsc, 1.0)
}

/// [`m0_newmark_system`] with the friction stiffness KR scaled by `friction`.
fn m0_newmark_system_with_friction<'p>(
    petsc: &'p Petsc,
    friction: f64,
) -> TestResult<(SparseMatrix<'p>, Vector<'p>)> {
    let (h, beta, gamma, omega) = (1e-6, 0.25, 0.5, 4.0 * std::f64::consts::PI);
    let term = |f: &str, c: f64| MatrixTerm {
        file: PathBuf::from(f),
        coefficient: c,
        speed_power: 0,
    };
    let c1 = gamma / (beta * h);
    let terms = [
        term("M.mtx.gz", 1.0 / (beta * h * h)),
        term("D1.mtx.gz", c1),
        term("DG.mtx.gz", c1 * omega),
        term("K1.mtx.gz", 1.0),
        term("KR.mtx.gz", friction),
    ];
    let j = load_sum(petsc, &terms, &data_dir())?;
    if j.asymmetry.is_nan() || j.asymmetry < 1e-12 {
        return Err(format!(
            "J should be unsymmetric (friction), asymmetry {:e}",
            j.asymmetry
        )
        .into());
    }
    let j = j.matrix;
    // x_true with entries of both signs and several magnitudes; b = J x_true.
    let mut x_true = j.new_vector()?;
    let range = x_true.ownership();
    {
        let mut local = x_true.local_mut()?;
        for (k, v) in local.iter_mut().enumerate() {
            let i = (range.start + k) as f64;
            *v = (0.37 * i).sin() * (1.0 + (i / 500.0).cos().powi(2) * 10.0);
        }
    }
    let mut b = x_true.duplicate()?;
    j.mult(&x_true, &mut b)?;
    Ok((j, b))
}

/// The Newmark Jacobian J = M / (beta h^2) + gamma / (beta h) D + K of brake M0 (Graebner et
/// al., ZAMM 2016; tests/data/brake-m0) at Omega = 4 pi rad/s with its friction (KR,
/// unsymmetric) and gyroscopic (DG) terms, h = 1 us: the system the transient solves at every
/// iteration. PETSc's LU on every rank pivots only on the diagonal; for a matrix whose diagonal
/// dominates (the mass term at small h) Wilkinson's bound keeps the growth factor small and
/// the normwise backward error |b - J x|_inf / (|J|_inf |x|_inf + |b|_inf) at a modest
/// multiple of n_row eps (n_row <= 200 entries per row here: ~4e-14); asserted below 1e-12,
/// as for MUMPS with its pivoting on the same system. The two solutions then agree within
/// cond(J) times that (cond_inf(J) ~ 1e2 here, from the mass-dominated diagonal): 1e-9.
fn brake_m0_newmark_jacobian_per_rank_lu_backward_stable(petsc: &Petsc) -> TestResult {
    let (j, b) = m0_newmark_system(petsc)?;
    let j_inf = j.norm_infinity()?;
    let b_inf = b.norm_inf()?;
    let solve = |per_rank: bool| -> TestResult<(Vector<'_>, f64)> {
        let factor = if per_rank {
            DirectSolver::factorize_per_rank(petsc, &j, "m0_per_rank_")
        } else {
            DirectSolver::factorize(petsc, &j, Factorization::Lu, "m0_mumps_")
        }?;
        let mut x = b.duplicate()?;
        factor.solve(&b, &mut x)?;
        let mut r = b.duplicate()?;
        j.mult(&x, &mut r)?;
        r.axpy(-1.0, &b)?;
        let x_inf = x.norm_inf()?;
        let backward = r.norm_inf()? / (j_inf * x_inf + b_inf);
        Ok((x, backward))
    };
    let (x_lu, backward_lu) = solve(true)?;
    let (x_mumps, backward_mumps) = solve(false)?;
    let mut d = x_lu.try_clone()?;
    d.axpy(-1.0, &x_mumps)?;
    let difference = d.norm_inf()? / x_mumps.norm_inf()?;
    say(
        petsc,
        &format!(
            "M0 Newmark J (h = 1 us, friction): backward error per-rank LU {backward_lu:.2e}, MUMPS {backward_mumps:.2e}; solutions differ by {difference:.2e}"
        ),
    );
    let bad = |x: f64, bound: f64| x.is_nan() || x > bound;
    if bad(backward_lu, 1e-12) || bad(backward_mumps, 1e-12) || bad(difference, 1e-9) {
        return Err(format!(
            "backward errors {backward_lu:e} (per-rank LU), {backward_mumps:e} (MUMPS), difference {difference:e}"
        ).into());
    }
    Ok(())
}

/// The same Jacobian factorized by MUMPS in single precision (libsmumps: the transient's
/// `jacobian_factor = "single"`). Bound: the argument above with u = 2^-24 = 5.96e-8 in place
/// of eps (and the rounding of J's entries to single precision, a relative perturbation of u
/// per entry, inside it): one solve's normwise backward error at most n_row u = 1.2e-5. The
/// transient uses the factor inside an iteration whose residual is in double precision; that
/// iteration (here x += F^-1 (b - J x), the modified Newton step of a linear problem)
/// contracts the error by about cond(J) u ~ 1e-5 per step, so from 1.2e-5 it must reach the
/// double-precision bound above (1e-12) within 3 steps, and then agree with MUMPS' double
/// factor's solution within 1e-9 as above.
fn brake_m0_newmark_jacobian_single_precision_mumps(petsc: &Petsc) -> TestResult {
    let (j, b) = m0_newmark_system(petsc)?;
    let j_inf = j.norm_infinity()?;
    let b_inf = b.norm_inf()?;
    let backward = |x: &Vector, r: &mut Vector| -> TestResult<f64> {
        j.mult(x, r)?;
        r.axpy(-1.0, &b)?;
        r.scale(-1.0)?;
        Ok(r.norm_inf()? / (j_inf * x.norm_inf()? + b_inf))
    };
    let single = DirectSolver::factorize_single(petsc, &j, Factorization::Lu, "m0_single_")?;
    let double = DirectSolver::factorize(petsc, &j, Factorization::Lu, "m0_double_")?;
    let mut x = b.duplicate()?;
    let mut r = b.duplicate()?;
    // The solve with MUMPS' one-column GEMMs sent to GEMV (la::one_column_gemm, the default)
    // and with the library's GEMM: both within the bound; forwarded calls counted over the
    // ranks (none would mean the executable does not interpose the symbol).
    one_column_gemm::set_forwarding(false);
    single.solve(&b, &mut x)?;
    let first_library = backward(&x, &mut r)?;
    one_column_gemm::set_forwarding(true);
    let before = one_column_gemm::calls().0;
    single.solve(&b, &mut x)?;
    let forwarded_here = one_column_gemm::calls().0 - before;
    let mut forwarded = 0u64;
    petsc
        .world()
        .all_reduce_into(&forwarded_here, &mut forwarded, SystemOperation::sum());
    let first = backward(&x, &mut r)?;
    let mut dx = b.duplicate()?;
    let (mut refined, mut steps) = (first, 0);
    while (refined > 1e-12 || refined.is_nan()) && steps < 3 {
        single.solve(&r, &mut dx)?;
        x.axpy(1.0, &dx)?;
        refined = backward(&x, &mut r)?;
        steps += 1;
    }
    let mut reference = b.duplicate()?;
    double.solve(&b, &mut reference)?;
    x.axpy(-1.0, &reference)?;
    let difference = x.norm_inf()? / reference.norm_inf()?;
    let report = single.report();
    say(
        petsc,
        &format!(
            "M0 Newmark J in single precision: {:.3e} factor entries ({:.1} MB of values; double: {:.3e} entries), one solve's backward error {first:.2e} with {forwarded} GEMM/TRSM calls sent to GEMV/TRSV, {first_library:.2e} with the library's routines (bound 1.2e-5); {refined:.2e} after {steps} refinement steps in double precision (bound 1e-12 within 3); against MUMPS in double {difference:.2e} (bound 1e-9)",
            report.factor_entries,
            report.factor_entries * 4.0 / 1e6,
            double.report().factor_entries
        ),
    );
    let bad = |x: f64, bound: f64| x.is_nan() || x > bound;
    if forwarded == 0 {
        return Err("no GEMM or TRSM of the single-precision solve reached la::one_column_gemm (are the symbols exported? src/build.rs)".into());
    }
    if bad(first, 1.2e-5)
        || bad(first_library, 1.2e-5)
        || bad(refined, 1e-12)
        || bad(difference, 1e-9)
    {
        return Err(format!(
            "single precision: backward error {first:e} ({first_library:e} with the library's GEMM), refined {refined:e} after {steps} steps, difference {difference:e}"
        ).into());
    }
    Ok(())
}

/// The single-precision factor renewed in place (the transient's refreshed Jacobian: new
/// values on the pattern of the first, MUMPS' numerical phase on the first analysis): J's
/// values are overwritten by those of J with twice the friction stiffness KR (same pattern),
/// the factor renewed, and one solve of the new system must meet the single-precision bound
/// of the test above (n_row u = 1.2e-5), which the old factor misses by orders of magnitude
/// (checked, so the renewal is not vacuous); another matrix is refused.
fn brake_m0_single_precision_factor_renewed_in_place(petsc: &Petsc) -> TestResult {
    let (mut j, _) = m0_newmark_system(petsc)?;
    let (j2, b2) = m0_newmark_system_with_friction(petsc, 2.0)?;
    let mut factor = DirectSolver::factorize_single(petsc, &j, Factorization::Lu, "m0_renewed_")?;
    j.copy_values_from(&j2)?;
    let (j_inf, b_inf) = (j.norm_infinity()?, b2.norm_inf()?);
    let backward = |factor: &DirectSolver| -> TestResult<f64> {
        let mut x = b2.duplicate()?;
        factor.solve(&b2, &mut x)?;
        let mut r = b2.duplicate()?;
        j.mult(&x, &mut r)?;
        r.axpy(-1.0, &b2)?;
        Ok(r.norm_inf()? / (j_inf * x.norm_inf()? + b_inf))
    };
    let stale = backward(&factor)?;
    let renews = factor.factors(&j)?;
    factor.refactorize(&j)?;
    let renewed = backward(&factor)?;
    let refused = factor.refactorize(&j2).is_err() && !factor.factors(&j2)?;
    say(
        petsc,
        &format!("M0 Newmark J, friction doubled in place: the old single-precision factor's backward error {stale:.2e}, renewed {renewed:.2e} (bound 1.2e-5); another matrix refused: {refused}"),
    );
    check_le("backward error of the renewed factor", renewed, 1.2e-5)?;
    // NaN in either fails here too.
    if stale.is_nan() || stale <= 100.0 * renewed {
        return Err(format!(
            "the old factor solves the new system nearly as well ({stale:e} vs {renewed:e}): the test does not see a renewal"
        ).into());
    }
    match (renews, refused) {
        (false, _) => Err("the factor does not recognize its own matrix".into()),
        (_, false) => Err("a factor was renewed from another matrix".into()),
        _ => Ok(()),
    }
}

/// A banded n x n matrix (|i - j| <= band) of this rank's rows `local`, entries `value(i, j)`.
fn banded<'p>(
    petsc: &'p Petsc,
    n: usize,
    local: std::ops::Range<usize>,
    band: usize,
    value: impl Fn(usize, usize) -> f64,
) -> TestResult<SparseMatrix<'p>> {
    let columns = |i: usize| i.saturating_sub(band)..(i + band + 1).min(n);
    let p = Preallocation {
        diag: local
            .clone()
            .map(|i| columns(i).filter(|j| local.contains(j)).count() as i32)
            .collect(),
        off: local
            .clone()
            .map(|i| columns(i).filter(|j| !local.contains(j)).count() as i32)
            .collect(),
        diag_upper: vec![0; local.len()],
        off_upper: vec![0; local.len()],
    };
    let mut a = SparseMatrix::new(petsc, MatrixFormat::Aij, 1, local.len(), &p)?;
    for i in local {
        for j in columns(i) {
            a.add_values(&[i as i32], &[j as i32], &[value(i, j)])?;
        }
    }
    a.assemble()?;
    Ok(a)
}

/// The largest |a_ij - expected(i, j)| over this rank's rows, every stored entry (NaN counts).
fn entry_error(a: &SparseMatrix, expected: impl Fn(usize, usize) -> f64) -> TestResult<f64> {
    let mut worst = 0.0f64;
    a.for_each_local_row(|i, cols, vals| {
        for (&j, &v) in cols.iter().zip(vals) {
            worst = nan_max(worst, (v - expected(i, j as usize)).abs());
        }
    })?;
    Ok(worst)
}

/// `copy_values_from` and `axpy_subset` move a tridiagonal matrix's values into a
/// pentadiagonal one's pattern by PETSc's CSR arrays (src/la/csr.rs): the entries must be
/// exactly B's (zero outside its band) and A - B/2 exactly; the rows near the ranks' split
/// hold off-rank columns (PETSc's off-diagonal block and its column map). A MUMPS factor of A
/// renewed after a copy must factor the new values (the copy advances A's state: a factor
/// that skipped it would solve with the old B): x = 1 from b = B' 1 to 1e-12 (B' diagonally
/// dominant, condition number < 3). A tridiagonal destination is not a superset of a
/// pentadiagonal source: every rank gets an error, none hangs.
fn nested_pattern_copy_and_axpy_set_exact_entries_and_a_refactorization_sees_them(
    petsc: &Petsc,
) -> TestResult {
    let n = 40;
    let (size, rank) = (petsc.size() as usize, petsc.rank() as usize);
    let local = rank * n / size..(rank + 1) * n / size;
    let b_value = |i: usize, j: usize| {
        if i == j {
            10.0 + i as f64
        } else {
            -1.0 - 0.01 * (i + j) as f64
        }
    };
    let in_band = |i: usize, j: usize| i.abs_diff(j) <= 1;
    let b = banded(petsc, n, local.clone(), 1, b_value)?;
    let mut a = banded(petsc, n, local.clone(), 2, |i, j| {
        1000.0 + i as f64 + 0.1 * j as f64
    })?;
    a.copy_values_from(&b)?;
    let b_in_a = |i: usize, j: usize| if in_band(i, j) { b_value(i, j) } else { 0.0 };
    let copied = entry_error(&a, b_in_a)?;
    // A factor of A = B now, then A := B + 5 I through a second copy, renewed.
    let mut solver = DirectSolver::factorize(petsc, &a, Factorization::Lu, "nested_")?;
    let shifted = |i: usize, j: usize| b_value(i, j) + if i == j { 5.0 } else { 0.0 };
    let b2 = banded(petsc, n, local.clone(), 1, shifted)?;
    a.copy_values_from(&b2)?;
    solver.refactorize(&a)?;
    let solve_error = error_solving_for_ones(&solver, &b2)?;
    a.axpy_subset(-0.5, &b2)?;
    let halved = entry_error(&a, |i, j| {
        0.5 * if in_band(i, j) { shifted(i, j) } else { 0.0 }
    })?;
    let mut narrow = banded(petsc, n, local.clone(), 1, |_, _| 1.0)?;
    let wide = banded(petsc, n, local, 2, |_, _| 2.0)?;
    let refused = narrow.copy_values_from(&wide).is_err();
    say(
        petsc,
        &format!("copy {copied:.1e}, axpy {halved:.1e}, solve after the renewed factor {solve_error:.1e}, wider source refused: {refused}"),
    );
    check_le("copied entries", copied, 0.0)?;
    check_le("entries after axpy", halved, 0.0)?;
    check_le("solution error with the renewed factor", solve_error, 1e-12)?;
    match refused {
        true => Ok(()),
        false => Err("a wider pattern was copied into a narrower one without an error".into()),
    }
}

/// The block of a pentadiagonal matrix at indices spread over the ranks' rows (9, 10, 11:
/// entries off the diagonal inside the block; 19, 20, 22: across the two-rank split at 20)
/// equals its entries exactly, zero outside the band, and is the same on every rank.
fn block_holds_the_entries_of_its_rows_and_columns(petsc: &Petsc) -> TestResult {
    let n = 40;
    let (size, rank) = (petsc.size() as usize, petsc.rank() as usize);
    let local = rank * n / size..(rank + 1) * n / size;
    let value = |i: usize, j: usize| 1.0 + i as f64 + 0.01 * j as f64;
    let a = banded(petsc, n, local, 2, value)?;
    let indices = [0, 9, 10, 11, 19, 20, 22, 39];
    // Column-major: block[c * n + r] is row r, column c.
    let block = a.block(&indices)?.dense_columns();
    let mut worst = 0.0f64;
    for (r, &i) in indices.iter().enumerate() {
        for (c, &j) in indices.iter().enumerate() {
            let expected = if i.abs_diff(j) <= 2 { value(i, j) } else { 0.0 };
            worst = nan_max(worst, (block[c * indices.len() + r] - expected).abs());
        }
    }
    let mut sums = vec![0.0; size];
    sums[rank] = block.iter().sum();
    squeal::parallel::sum_in_place(petsc.world(), &mut sums);
    let same = sums.iter().all(|&s| s == sums[0]);
    say(
        petsc,
        &format!("block: max entry error {worst:.1e}, the same on every rank: {same}"),
    );
    check_le("block entry error", worst, 0.0)?;
    if !same {
        return Err("the block differs between ranks".into());
    }
    Ok(())
}

/// A block of brake M0's Newmark Jacobian (the system of the test above; Graebner et al., ZAMM
/// 2016), its unknowns 1,500-2,699 (a coupled patch of its mesh), as a nonlinear elimination's
/// local Jacobian is a block of the reduced one: the local sparse LU (PETSc's sequential LU, nested dissection,
/// no pivoting) solves it with a normwise backward error below 1e-12 (the argument of
/// `brake_m0_newmark_jacobian_per_rank_lu_backward_stable`: a mass-dominated diagonal keeps
/// the growth small; n_row eps ~ 4e-14), as LAPACK's pivoted dense LU does, the two solutions
/// within cond times that (1e-9). Refactored in place with other values in the same pattern
/// (the diagonal doubled, the rest halved: the numerical phase alone, as an elimination's
/// next local Jacobian), it solves that matrix to the same bound. A matrix with a zero
/// diagonal ([[0, 1], [1, 0]]) is reported as needing pivoting (None), not factored into
/// garbage, and so is a refactor to it. Every rank gets the same block.
fn brake_m0_newmark_block_local_sparse_lu_backward_stable(petsc: &Petsc) -> TestResult {
    use squeal::la::lapack::RealLu;
    use squeal::la::local_lu::{Csr, LocalLu};
    let (j, _) = m0_newmark_system(petsc)?;
    let indices: Vec<usize> = (1500..2700.min(j.global_rows())).collect();
    let n = indices.len();
    let block = j.block(&indices)?;
    let x_true: Vec<f64> = (0..n)
        .map(|i| (0.37 * i as f64).sin() * (1.0 + (i as f64 / 50.0).cos().powi(2) * 10.0))
        .collect();
    let mut b = vec![0.0; n];
    block.mult_add(&x_true, &mut b);
    let inf = |v: &[f64]| v.iter().fold(0.0f64, |m, x| nan_max(m, x.abs()));
    let row_sums: Vec<f64> = (0..n)
        .map(|i| {
            block.values[block.row_start[i]..block.row_start[i + 1]]
                .iter()
                .map(|v| v.abs())
                .sum()
        })
        .collect();
    let backward = |x: &[f64]| {
        let mut r: Vec<f64> = b.iter().map(|v| -v).collect();
        block.mult_add(x, &mut r);
        inf(&r) / (inf(&row_sums) * inf(x) + inf(&b))
    };
    let mut sparse = LocalLu::new(petsc, &block)?
        .ok_or("the local sparse LU met a zero pivot on a mass-dominated Jacobian")?;
    let mut x_sparse = b.clone();
    sparse.solve(&mut x_sparse)?;
    let factor_entries = sparse.factor_entries();
    let mut other = block.clone();
    for i in 0..n {
        for k in other.row_start[i]..other.row_start[i + 1] {
            other.values[k] *= if other.columns[k] == i { 2.0 } else { 0.5 };
        }
    }
    if !sparse.refactor(&other.values)? {
        return Err("the refactored LU met a zero pivot on a mass-dominated Jacobian".into());
    }
    let mut b_other = vec![0.0; n];
    other.mult_add(&x_true, &mut b_other);
    let mut x_other = b_other.clone();
    sparse.solve(&mut x_other)?;
    let backward_refactored = {
        let mut r: Vec<f64> = b_other.iter().map(|v| -v).collect();
        other.mult_add(&x_other, &mut r);
        let rows = (0..n).fold(0.0f64, |m, i| {
            let sum = other.values[other.row_start[i]..other.row_start[i + 1]]
                .iter()
                .map(|v| v.abs())
                .sum::<f64>();
            nan_max(m, sum)
        });
        inf(&r) / (rows * inf(&x_other) + inf(&b_other))
    };
    let dense = RealLu::new(n, block.dense_columns())?;
    let mut x_dense = b.clone();
    dense.solve(&mut x_dense)?;
    let difference = x_sparse
        .iter()
        .zip(&x_dense)
        .fold(0.0f64, |m, (a, b)| nan_max(m, (a - b).abs()))
        / inf(&x_dense);
    let (backward_sparse, backward_dense) = (backward(&x_sparse), backward(&x_dense));
    // (Its zero diagonal stored: the numerical pivot test, not the pattern's.)
    let swap = Csr::from_triplets(2, vec![(0, 0, 0.0), (0, 1, 1.0), (1, 0, 1.0), (1, 1, 0.0)]);
    let zero_pivot_seen = LocalLu::new(petsc, &swap)?.is_none();
    let regular = Csr::from_triplets(2, vec![(0, 0, 2.0), (0, 1, 1.0), (1, 0, 1.0), (1, 1, 2.0)]);
    let mut to_swap = LocalLu::new(petsc, &regular)?.ok_or("[[2, 1], [1, 2]] met a zero pivot")?;
    let refactor_zero_pivot_seen = !to_swap.refactor(&swap.values)?;
    let mut sums = vec![0.0; petsc.size() as usize];
    sums[petsc.rank() as usize] = x_sparse.iter().sum();
    squeal::parallel::sum_in_place(petsc.world(), &mut sums);
    let same = sums.iter().all(|&s| s == sums[0]);
    say(
        petsc,
        &format!(
            "M0 Newmark J, block of {n} unknowns ({} entries, sparse factor {factor_entries:.0}): backward error sparse LU {backward_sparse:.2e}, refactored {backward_refactored:.2e}, dense LU {backward_dense:.2e}; solutions differ by {difference:.2e}; zero pivot reported: {zero_pivot_seen}, at a refactor: {refactor_zero_pivot_seen}; same on every rank: {same}",
            block.values.len(),
        ),
    );
    check_le("sparse LU backward error", backward_sparse, 1e-12)?;
    check_le(
        "refactored sparse LU backward error",
        backward_refactored,
        1e-12,
    )?;
    check_le("dense LU backward error", backward_dense, 1e-12)?;
    check_le("sparse against dense solution", difference, 1e-9)?;
    if !zero_pivot_seen || !refactor_zero_pivot_seen {
        return Err("a zero diagonal was factored without a report".into());
    }
    if !same {
        return Err("the local solutions differ between ranks".into());
    }
    Ok(())
}
