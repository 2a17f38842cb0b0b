//! Tests of the MPI suite, grouped by the reference they reproduce.

pub mod common;
pub mod complex_modes;
pub mod contact_statics;
pub mod convergence;
pub mod dense_reference;
pub mod growth;
pub mod link;
pub mod loudness;
pub mod mode_coupling;
pub mod noise_matrix;
pub mod parallel_and_solvers;
pub mod pseudo_trajectory;
pub mod real_modes_verification;
pub mod reduction;
pub mod single_precision;
pub mod stages;
pub mod static_solve;
pub mod stick_slip;
pub mod time_integration;
pub mod tolerance_reference;

use std::time::Duration;

use squeal::la::Petsc;

/// What a test returns: Ok, or what went wrong (any error converts with `?`).
pub type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// A test: its name and a function that returns Ok or what went wrong.
pub type NamedTest = (&'static str, fn(&Petsc) -> TestResult);

pub fn all() -> Vec<NamedTest> {
    let mut v: Vec<NamedTest> = Vec::new();
    v.extend(real_modes_verification::tests());
    v.extend(convergence::tests());
    v.extend(parallel_and_solvers::tests());
    v.extend(single_precision::tests());
    v.extend(static_solve::tests());
    v.extend(contact_statics::tests());
    v.extend(complex_modes::tests());
    v.extend(dense_reference::tests());
    v.extend(time_integration::tests());
    v.extend(tolerance_reference::tests());
    v.extend(reduction::tests());
    v.extend(stages::tests());
    v.extend(stick_slip::tests());
    v.extend(mode_coupling::tests());
    v.extend(loudness::tests());
    v.extend(growth::tests());
    v.extend(link::tests());
    v.extend(pseudo_trajectory::tests());
    v.extend(noise_matrix::tests());
    v
}

/// How long a test may run before the suite's watchdog aborts it: about 5x its time measured on
/// 2 cores (1 and 2 ranks, the slower), at least 60 s; 3x that on more ranks than the 2 cores
/// (oversubscribed, every rank then gets part of a core).
pub fn time_limit(name: &str, ranks: i32) -> Duration {
    let seconds = LONG_TESTS
        .iter()
        .find(|(long, _)| *long == name)
        .map_or(60, |&(_, s)| s);
    Duration::from_secs(if ranks > 2 { 3 * seconds } else { seconds })
}

/// Part `k` of `parts` of `tests`, balanced by expected time (longest first, each to the part
/// with the least so far; a test not in LONG_TESTS counts as 2 s). Deterministic, so every
/// part's run knows the same split.
pub fn shard(tests: Vec<NamedTest>, k: usize, parts: usize) -> Vec<NamedTest> {
    let weight = |name: &str| {
        LONG_TESTS
            .iter()
            .find(|(long, _)| *long == name)
            .map_or(2, |&(_, limit)| limit / 5)
    };
    let mut order: Vec<usize> = (0..tests.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(weight(tests[i].0)));
    let mut load = vec![0u64; parts];
    let mut part_of = vec![0; tests.len()];
    for i in order {
        let lightest = (0..parts).min_by_key(|&p| (load[p], p)).unwrap_or(0);
        load[lightest] += weight(tests[i].0);
        part_of[i] = lightest;
    }
    tests
        .into_iter()
        .zip(part_of)
        .filter(|&(_, p)| p == k)
        .map(|(t, _)| t)
        .collect()
}

/// The tests that took longer than 12 s on 1 or 2 ranks, with their limit in seconds and, in
/// the comment, the slowest time measured (some with a build running on the same 2 cores).
const LONG_TESTS: &[(&str, u64)] = &[
    (
        "popp_stelter_belt_stick_slip_converges_to_the_coulomb_cycle",
        600,
    ), // 149 s
    (
        "hoffmann_mode_coupling_saturates_by_separation_with_balanced_energy",
        330,
    ), // 66 s
    (
        "small_brake_transient_grows_at_the_rate_of_its_unstable_complex_mode",
        300,
    ), // 54 s
    (
        "hoffmann_pseudo_trajectory_alpha_sat_against_the_limit_cycle_amplitude",
        240,
    ), // 47 s
    (
        "graebner_m0_complex_modes_at_4pi_band_stable_under_settings",
        240,
    ), // 47 s
    (
        "brake_projected_complex_modes_match_full_and_converge_with_basis",
        240,
    ), // 44 s
    ("free_beam_convergence_rates", 180), // 37 s
    (
        "reduced_brake_has_the_full_real_modes_and_follows_the_full_transient",
        180,
    ), // 32 s
    ("brake_transient_fixed_jacobian_follows_full_newton", 180), // 32 s
    (
        "brake_transient_updated_factor_follows_full_newton_where_contact_opens",
        180,
    ), // ~25 s
    ("newmark_exponential_contact_oscillator_periods", 120), // 24 s
    (
        "brake_pseudo_trajectory_starts_at_the_nominal_mode_and_agrees_on_1_and_2_ranks",
        120,
    ), // 18 s
    ("brake_mu_sweep_reproduces_the_nominal_projected_modes", 90), // 17 s
    (
        "noise_matrix_slices_merge_to_the_whole_and_a_killed_run_resumes",
        170,
    ), // 34 s (beside another 2-rank job)
    (
        "noise_matrix_points_equal_single_scene_runs_and_the_nominal_modes",
        110,
    ), // 22 s (beside another 2-rank job)
    (
        "noise_matrix_saturation_at_the_nominal_point_is_the_pseudo_trajectory_and_loudness_stages",
        100,
    ), // 20 s
    (
        "brake_transient_impulse_start_moves_along_the_impulse_and_scales_with_it",
        90,
    ), // 16 s
    ("annular_plate_clamped_inner_leissa", 90), // 15 s
    (
        "small_brake_complex_modes_against_a_dense_solve_of_the_exported_linearization",
        300,
    ),
];
