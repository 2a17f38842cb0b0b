//! Measured convergence of the first elastic frequency of a free-free beam under uniform mesh
//! refinement, per element type, with the observed order from three meshes (Richardson:
//! p = log2((f2 - f4) / (f4 - f8)) for element sizes h/2, h/4, h/8), asserted against the theory for
//! eigenvalues of degree-k elements: error O(h^2k) in omega^2, hence O(h^2k) in the frequency
//! (Strang & Fix, "An analysis of the finite element method", 1973, ch. 6): order 2 for the
//! trilinear Hex8 and Hex8I and the linear Tet4, order 4 for the quadratic Hex20 and Tet10.
//!
//! Free-free, not clamped: a fully clamped solid end has edge singularities that cap every
//! element's rate (measured: Hex8I went non-monotone on the cantilever), whereas the free
//! beam's eigenfunction is smooth. The six rigid-body modes come first (shift below zero).

use super::TestResult;
use squeal::eigen::real_modes::RealModeRequest;
use squeal::la::Petsc;
use squeal::measure::exceeds;
use squeal::mesh::structured::block;
use squeal::mesh::ElementKind;

use super::common::{say, solve_modes, steel};

pub fn tests() -> Vec<super::NamedTest> {
    vec![("free_beam_convergence_rates", free_beam_convergence_rates)]
}

fn free_beam_convergence_rates(petsc: &Petsc) -> TestResult {
    let (l, b, h) = (1.0, 0.1, 0.1);
    say(petsc, "element  cells(k=1)  f(k=1)        f(k=2)        f(k=4)        f(k=8)        order k=2,4,8 (expected)");
    for (kind, base, expected) in [
        (ElementKind::Hex8, [8, 1, 1], 2.0),
        (ElementKind::Hex8I, [8, 1, 1], 2.0),
        (ElementKind::Hex20, [4, 1, 1], 4.0),
        (ElementKind::Tet10, [4, 1, 1], 4.0),
        (ElementKind::Tet4, [8, 1, 1], 2.0),
    ] {
        let mut f = Vec::new();
        for k in [1, 2, 4, 8] {
            let mesh = block([l, b, h], base.map(|n| n * k), kind, steel());
            let request = RealModeRequest {
                count: 7,
                tolerance: 1e-13,
                ..Default::default()
            };
            let (_, modes) = solve_modes(petsc, &mesh, &[], &request)?;
            let rigid = modes.rigid.iter().filter(|&&r| r).count();
            if rigid != 6 || modes.rigid[6] {
                return Err(format!(
                    "{kind:?}: {rigid} rigid-body modes, expected 6: {:?}",
                    modes.frequencies_hz
                )
                .into());
            }
            f.push(modes.frequencies_hz[6]);
        }
        let observed = |a: f64, b: f64, c: f64| ((a - b) / (b - c)).abs().log2();
        let (coarse, order) = (observed(f[0], f[1], f[2]), observed(f[1], f[2], f[3]));
        say(
            petsc,
            &format!(
                "{:7}  {:10}  {:.8}  {:.8}  {:.8}  {:.8}  {:.2} ({expected}; from k=1,2,4: {coarse:.2})",
                kind.name(),
                format!("{base:?}"),
                f[0],
                f[1],
                f[2],
                f[3],
                order
            ),
        );
        if f.iter().any(|x| x.is_nan()) || (f[1] - f[2]) * (f[2] - f[3]) <= 0.0 {
            return Err(format!("{kind:?}: not monotone: {f:?}").into());
        }
        // How far the observed order may still be from the theory. With an error
        // C h^p (1 + D h^q + ...), the observed order is p + O(h^q) and its distance from p
        // shrinks by 2^q per halving; so from k = 2, 4, 8 it is at most its change from the
        // coarser estimate (k = 1, 2, 4) for any q >= 1. Added: what the solver's tolerance
        // (1e-13 relative in each frequency) can do to the log of the ratio of differences.
        let noise = 2.0 * 1e-13 * f[3] / std::f64::consts::LN_2
            * (1.0 / (f[1] - f[2]).abs() + 1.0 / (f[2] - f[3]).abs());
        let window = (order - coarse).abs() + noise;
        if exceeds((order - expected).abs(), window) {
            return Err(format!(
                "{kind:?}: observed order {order:.2} (from k=1,2,4: {coarse:.2}), expected {expected} within {window:.2}"
            ).into());
        }
    }
    Ok(())
}
