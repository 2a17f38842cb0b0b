//! Mode tracking by MAC (modal assurance criterion) across a sequence of eigen-solutions in
//! one fixed basis: sweep points, or linearizations along a trajectory.

use crate::la::DenseError;
use crate::measure::{nan_max, nan_min};
use std::collections::BTreeMap;

use super::complex_modes::{companion, coordinates, solve_dense, Complex, DenseEigenpair};
use super::near_shift::eigenpairs_near;
use crate::la::hessenberg::EigenvaluesFirst;

/// Modal assurance criterion of two complex vectors: |a^H b|^2 / (|a|^2 |b|^2).
pub fn mac(a: &[(f64, f64)], b: &[(f64, f64)]) -> f64 {
    let (mut re, mut im, mut na, mut nb) = (0.0, 0.0, 0.0, 0.0);
    for (&(ar, ai), &(br, bi)) in a.iter().zip(b) {
        re += ar * br + ai * bi;
        im += ar * bi - ai * br;
        na += ar * ar + ai * ai;
        nb += br * br + bi * bi;
    }
    if na == 0.0 || nb == 0.0 {
        0.0
    } else {
        (re * re + im * im) / (na * nb)
    }
}

/// Mode tracks over the sweep points: `tracks[t][i]` is track t's eigenvalue at point i and
/// its MAC with the track's mode at the previous point (1 at the first point).
#[derive(Debug, Clone, Default)]
pub struct Tracks {
    pub tracks: Vec<Vec<Option<(Complex, f64)>>>,
}

/// Relative eigenvalue spacing below which modes form a cluster (a doublet of the disc).
const CLUSTER: f64 = 2e-3;

/// |t - s| / |s|: the pairing's distance term.
fn relative_distance(s: Complex, t: Complex) -> f64 {
    (s.0 - t.0).hypot(s.1 - t.1) / s.0.hypot(s.1).max(1e-300)
}

/// What [`pair_modes`] pays for continuing the mode at `s` by the one at `t` with MAC `mac`;
/// at least their relative distance, which is what proves a choice made among a subset.
fn choice_cost(s: Complex, t: Complex, mac: f64) -> f64 {
    (1.0 - mac) + relative_distance(s, t)
}

/// Pairs the modes of one point with those of the next: for each previous mode, the index of
/// its continuation and the MAC (or None). Greedy on the cost (1 - MAC) + |s_i - s_j| / |s_i|,
/// where for a mode inside a cluster (a doublet: eigenvalues within 2e-3) the MAC is taken
/// with the cluster's whole plane. So the shape decides at crossings (frequencies meet,
/// shapes differ), and inside a doublet, whose two shapes may rotate freely within their plane
/// from one point to the next, the eigenvalue decides: its tracks keep their order, no swaps.
pub fn pair_modes(
    previous: &[DenseEigenpair],
    next: &[DenseEigenpair],
) -> Vec<Option<(usize, f64)>> {
    let close = |a: Complex, b: Complex| {
        (a.0 - b.0).hypot(a.1 - b.1) <= CLUSTER * a.0.hypot(a.1).max(b.0.hypot(b.1))
    };
    let macs = mac_matrix(previous, next);
    let mut candidates = Vec::with_capacity(previous.len() * next.len());
    for (i, (si, _)) in previous.iter().enumerate() {
        let cluster: Vec<usize> = (0..previous.len())
            .filter(|&k| close(previous[k].0, *si))
            .collect();
        for (j, (sj, _)) in next.iter().enumerate() {
            let m = cluster
                .iter()
                .map(|&k| macs[k + j * previous.len()])
                .sum::<f64>()
                .min(1.0);
            candidates.push((choice_cost(*si, *sj, m), i, j, m));
        }
    }
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out = vec![None; previous.len()];
    let mut taken = vec![false; next.len()];
    for (_, i, j, m) in candidates {
        if out[i].is_none() && !taken[j] {
            out[i] = Some((j, m));
            taken[j] = true;
        }
    }
    out
}

/// [`mac`] of every previous mode with every next one (column-major, previous.len() rows),
/// by two real matrix products: with a = [Re a; Im a] and b = [Re b; Im b], Re(a^H b) = a^T b
/// and Im(a^H b) = a^T [Im b; -Re b]. A noise-matrix point pairs its ~250 modes with the
/// nominal ones: the pairwise loop took a quarter of the point's complex modes (perf,
/// 2026-11-27).
fn mac_matrix(previous: &[DenseEigenpair], next: &[DenseEigenpair]) -> Vec<f64> {
    let d = previous.first().or(next.first()).map_or(0, |p| p.1.len());
    let stacked = |modes: &[DenseEigenpair], turned: bool| -> Vec<f64> {
        let mut out = Vec::with_capacity(2 * d * modes.len());
        for (_, y) in modes {
            assert_eq!(y.len(), d, "pair_modes: vectors of one basis");
            match turned {
                false => out.extend(y.iter().map(|c| c.0).chain(y.iter().map(|c| c.1))),
                true => out.extend(y.iter().map(|c| c.1).chain(y.iter().map(|c| -c.0))),
            }
        }
        out
    };
    let a = stacked(previous, false);
    let (m, n) = (previous.len(), next.len());
    let re = crate::la::lapack::gemm_tn(2 * d, m, n, &a, &stacked(next, false));
    let im = crate::la::lapack::gemm_tn(2 * d, m, n, &a, &stacked(next, true));
    let norm2 = |y: &[Complex]| y.iter().map(|c| c.0 * c.0 + c.1 * c.1).sum::<f64>();
    let na: Vec<f64> = previous.iter().map(|p| norm2(&p.1)).collect();
    let nb: Vec<f64> = next.iter().map(|p| norm2(&p.1)).collect();
    let mut out = vec![0.0; m * n];
    for j in 0..n {
        for i in 0..m {
            let k = i + j * m;
            out[k] = match na[i] == 0.0 || nb[j] == 0.0 {
                true => 0.0,
                false => (re[k] * re[k] + im[k] * im[k]) / (na[i] * nb[j]),
            };
        }
    }
    out
}

/// Whether two eigenvalues form a flutter (mode-coupling) pair: locked to one frequency and
/// split in their real parts, both by the cluster spacing. (A doublet of the disc lies
/// within it, a crossing of two modes is split in frequency.)
pub fn flutter_pair(a: Complex, b: Complex) -> bool {
    let tolerance = CLUSTER * a.0.hypot(a.1).max(b.0.hypot(b.1));
    (a.1 - b.1).abs() <= tolerance && (a.0 - b.0).abs() > tolerance
}

/// The MAC with a member before the step above which a mode outside the tracked pair counts
/// as the member's continuation too: the two halves of a pair born at a coalescence inside
/// the step (on the brake's C35 at 4.6 um, 0.56 and 0.54) each carry part of the member.
const INHERITS: f64 = 0.25;

/// The mode's coupling pair after a step: `chosen[i]` is the continuation (index into
/// `next`) of `previous[i]`. Where the contact state decouples the pair, its two members
/// go on as separate modes, and one of them may couple with a third mode. Both halves of
/// that new flutter pair continue the member (they are born together at the coalescence,
/// either may be "the mode", as at the pair's own split), so the pair tracked becomes that
/// one: the member's continuation and the mode outside the pair (a flutter partner of it
/// with MAC >= INHERITS to the member) replace the members. Tracking one half only lost the
/// unstable one and made the mean damping depend on the phase where the period starts:
/// C35 at 4.6 um, 1 vs 2 ranks whose psi differ in sign, +3.3e-4 vs -7.8e-3. Unchanged
/// while the tracked members are themselves a flutter pair, or none couples.
pub fn coupling_pair(
    previous: &[DenseEigenpair],
    next: &[DenseEigenpair],
    chosen: &[usize],
) -> Vec<usize> {
    for (i, &j) in chosen.iter().enumerate() {
        let s = next[j].0;
        if chosen.iter().any(|&o| o != j && flutter_pair(s, next[o].0)) {
            continue;
        }
        let partner = (0..next.len())
            .filter(|k| !chosen.contains(k) && flutter_pair(s, next[*k].0))
            .map(|k| (mac(&previous[i].1, &next[k].1), k))
            .filter(|&(m, _)| m >= INHERITS)
            .max_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, k)) = partner {
            return vec![j, k];
        }
    }
    chosen.to_vec()
}

/// How many eigenvalues beyond the tracked pair [`near_pairs`] converges, first and at most:
/// more reach farther from the shift, so that a larger change between phases is still
/// proven to be the one the full pairing would choose.
const BEYOND: [usize; 2] = [1, 4];

/// Start vectors carried from one phase to the next.
pub const HINTS: usize = 8;

/// The `count` eigenpairs of `pairs` nearest any of `to`.
pub fn nearest(
    pairs: &[DenseEigenpair],
    to: &[DenseEigenpair],
    count: usize,
) -> Vec<DenseEigenpair> {
    let distance = |p: &DenseEigenpair| {
        to.iter()
            .map(|t| (p.0 .0 - t.0 .0).hypot(p.0 .1 - t.0 .1))
            .fold(f64::INFINITY, nan_min)
    };
    let mut order: Vec<(f64, usize)> = pairs.iter().map(distance).zip(0..).collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0));
    order
        .iter()
        .take(count)
        .map(|&(_, k)| pairs[k].clone())
        .collect()
}

/// Members of a tracked pair within this distance of their mean (relative to its modulus)
/// share one shift: a coupling pair's two modes share their frequency (on the brake's C35
/// they differ by ~2 % in |s|, mostly in the real part), so one factorization and one block
/// find both; farther apart (the pair has split), each member gets its own.
const SHARED_SHIFT: f64 = 0.05;

/// The shifts for the members of `current`: (shift, the members it serves).
fn shifts(current: &[DenseEigenpair]) -> Vec<(Complex, Vec<usize>)> {
    let n = current.len() as f64;
    let mean = current.iter().fold((0.0, 0.0), |acc, p| {
        (acc.0 + p.0 .0 / n, acc.1 + p.0 .1 / n)
    });
    let modulus = mean.0.hypot(mean.1);
    let close = current
        .iter()
        .all(|p| (p.0 .0 - mean.0).hypot(p.0 .1 - mean.1) <= SHARED_SHIFT * modulus);
    if close && current.len() > 1 {
        vec![(mean, (0..current.len()).collect())]
    } else {
        current
            .iter()
            .enumerate()
            .map(|(i, p)| (p.0, vec![i]))
            .collect()
    }
}

/// The eigenpairs of the projected system (`kp`, `cp`: m x m, unit mass) near the tracked
/// pair `current` (shift-invert at the pair's eigenvalues; `hints`: eigenpairs near the pair
/// at the previous point, to start from), when they provably hold the ones the MAC pairing
/// ([`pair_modes`]) would choose among all eigenpairs: an eigenvalue outside every radius
/// found costs more (by its distance alone) than each choice made inside, so the greedy
/// pairing makes the same choices before it reaches one. Else `None`: the caller solves the
/// whole dense problem. Small bases (where the full solve is as cheap) always get `None`.
pub fn pairs_near_tracked(
    m: usize,
    kp: &[f64],
    cp: &[f64],
    current: &[DenseEigenpair],
    hints: &[DenseEigenpair],
) -> Result<Option<Vec<DenseEigenpair>>, DenseError> {
    if m < 4 * (BEYOND[1] + 4) || current.is_empty() {
        return Ok(None);
    }
    'wider: for beyond in BEYOND {
        let mut found: Vec<DenseEigenpair> = Vec::new();
        let mut accurate: Vec<bool> = Vec::new();
        // Per member: the distance (relative to its eigenvalue) that anything outside the
        // eigenvalues found lies from it.
        let mut outside = vec![0.0; current.len()];
        for (shift, members) in shifts(current) {
            let mut start: Vec<DenseEigenpair> =
                members.iter().map(|&i| current[i].clone()).collect();
            start.extend(nearest(hints, &start, HINTS));
            let tracked = members.len();
            let Some(near) = eigenpairs_near(m, kp, cp, shift, &start, tracked, beyond)? else {
                continue 'wider;
            };
            for &i in &members {
                let s = current[i].0;
                let offset = (s.0 - shift.0).hypot(s.1 - shift.1);
                outside[i] = (near.radius - offset) / s.0.hypot(s.1).max(1e-300);
            }
            for (pair, exact) in near.pairs.into_iter().zip(near.accurate) {
                let t = pair.0;
                let same = |q: &DenseEigenpair| {
                    (q.0 .0 - t.0).hypot(q.0 .1 - t.1) <= 1e-9 * t.0.hypot(t.1)
                };
                match found.iter().position(same) {
                    // The same eigenvalue from two shifts: keep the converged one.
                    Some(k) if exact && !accurate[k] => {
                        found[k] = pair;
                        accurate[k] = true;
                    }
                    Some(_) => {}
                    None => {
                        found.push(pair);
                        accurate.push(exact);
                    }
                }
            }
        }
        // A continuation only located (not converged) is converged at its own eigenvalue (a
        // shift that close takes a few iterations), and the pairing made again.
        let mut choices = pair_modes(current, &found);
        for _ in 0..2 {
            let inexact: Vec<usize> = choices
                .iter()
                .flatten()
                .map(|&(j, _)| j)
                .filter(|&j| !accurate[j])
                .collect();
            if inexact.is_empty() {
                break;
            }
            for j in inexact {
                let s = found[j].0;
                let start = std::slice::from_ref(&found[j]);
                let Some(near) = eigenpairs_near(m, kp, cp, s, start, 1, 0)? else {
                    continue 'wider;
                };
                let same = |t: Complex| (t.0 - s.0).hypot(t.1 - s.1) <= 1e-6 * s.0.hypot(s.1);
                let Some(pair) = near
                    .pairs
                    .into_iter()
                    .zip(near.accurate)
                    .find_map(|(pair, exact)| (exact && same(pair.0)).then_some(pair))
                else {
                    continue 'wider;
                };
                found[j] = pair;
                accurate[j] = true;
            }
            choices = pair_modes(current, &found);
        }
        let mut worst_choice = 0.0f64;
        for (i, choice) in choices.into_iter().enumerate() {
            // Still only located: not the dense solve's pair to round-off.
            let Some((j, mac)) = choice.filter(|&(j, _)| accurate[j]) else {
                continue 'wider;
            };
            worst_choice = nan_max(worst_choice, choice_cost(current[i].0, found[j].0, mac));
        }
        if outside.iter().all(|&r| worst_choice < r) {
            return Ok(Some(found));
        }
    }
    Ok(None)
}

/// The eigenpairs of the projected system that the MAC pairing of `current` needs, from all
/// its eigenvalues (the whole problem, solved without vectors) and the vectors of those
/// nearest each member only: at least the `HINTS` nearest, and every eigenvalue nearer a
/// member than the costliest choice the pairing makes among them (the argument of
/// [`pairs_near_tracked`], here with every eigenvalue known). The pairing is then the one the
/// full dense solve gives, at about two thirds of its cost on the brake's 250 modes, where
/// shift-invert near the pair cannot prove its choice (the mode changes much between phases).
pub fn pairs_from_all_eigenvalues(
    m: usize,
    kp: &[f64],
    cp: &[f64],
    current: &[DenseEigenpair],
) -> Result<Vec<DenseEigenpair>, DenseError> {
    if current.is_empty() {
        return solve_dense(m, kp, cp);
    }
    let (a, omega_r) = companion(m, kp, cp);
    let all = EigenvaluesFirst::new(2 * m, a)?;
    // The eigenvalues with Im >= 0, as the full solve reports them.
    let upper: Vec<(usize, Complex)> = all
        .values
        .iter()
        .enumerate()
        .filter(|(_, v)| v.1 >= 0.0)
        .map(|(j, &(re, im))| (j, (re * omega_r, im * omega_r)))
        .collect();
    // Per member, the eigenvalues by distance.
    let by_distance: Vec<Vec<(f64, usize)>> = (0..current.len())
        .map(|i| {
            let mut d: Vec<(f64, usize)> = (0..upper.len())
                .map(|k| (relative_distance(current[i].0, upper[k].1), k))
                .collect();
            d.sort_by(|a, b| a.0.total_cmp(&b.0));
            d
        })
        .collect();
    // Vectors computed so far (None: no coordinates, skipped as the full solve skips it).
    let mut computed: BTreeMap<usize, Option<DenseEigenpair>> = BTreeMap::new();
    let (mut reach, mut worst) = (HINTS, 0.0f64);
    loop {
        let wanted: Vec<usize> = by_distance
            .iter()
            .flat_map(|d| {
                d.iter()
                    .enumerate()
                    .take_while(move |&(rank, &(dist, _))| rank < reach || dist <= worst)
                    .map(|(_, &(_, k))| k)
            })
            .filter(|k| !computed.contains_key(k))
            .collect::<std::collections::BTreeSet<usize>>()
            .into_iter()
            .collect();
        let indices: Vec<usize> = wanted.iter().map(|&k| upper[k].0).collect();
        for (&k, z) in wanted.iter().zip(all.vectors(&indices)?) {
            computed.insert(k, coordinates(m, &z).map(|y| (upper[k].1, y)));
        }
        let pairs: Vec<DenseEigenpair> = computed.values().flatten().cloned().collect();
        if computed.len() == upper.len() {
            return Ok(pairs);
        }
        let choices = pair_modes(current, &pairs);
        let costs: Option<Vec<f64>> = choices
            .iter()
            .enumerate()
            .map(|(i, c)| c.map(|(j, mac)| choice_cost(current[i].0, pairs[j].0, mac)))
            .collect();
        if let Some(costs) = costs {
            worst = costs.into_iter().fold(0.0, nan_max);
            // The nearest eigenvalue without a vector, per member, lies beyond every choice.
            let proven = by_distance.iter().all(|d| {
                d.iter()
                    .find(|(_, k)| !computed.contains_key(k))
                    .is_none_or(|&(dist, _)| worst < dist)
            });
            if proven {
                return Ok(pairs);
            }
        }
        reach *= 2;
    }
}

/// Tracks modes through the points (each point's modes with their modal coordinates in one
/// fixed basis). Tracks start at the first point; a mode of a later point that continues no
/// track is dropped (its track would start mid-sweep).
pub fn track(points: &[Vec<DenseEigenpair>]) -> Tracks {
    let Some(first) = points.first() else {
        return Tracks::default();
    };
    let mut tracks: Vec<Vec<Option<(Complex, f64)>>> =
        first.iter().map(|(s, _)| vec![Some((*s, 1.0))]).collect();
    // The current mode of each track (index into the latest point), None once lost.
    let mut current: Vec<Option<usize>> = (0..first.len()).map(Some).collect();
    for w in points.windows(2) {
        let (prev, next) = (&w[0], &w[1]);
        let alive: Vec<usize> = current.iter().filter_map(|c| *c).collect();
        let subset: Vec<DenseEigenpair> = alive.iter().map(|&i| prev[i].clone()).collect();
        let pairs = pair_modes(&subset, next);
        let by_prev: std::collections::HashMap<usize, Option<(usize, f64)>> =
            alive.iter().copied().zip(pairs).collect();
        for (t, c) in current.iter_mut().enumerate() {
            match c.and_then(|i| by_prev.get(&i).copied().flatten()) {
                Some((j, m)) => {
                    tracks[t].push(Some((next[j].0, m)));
                    *c = Some(j);
                }
                None => {
                    tracks[t].push(None);
                    *c = None;
                }
            }
        }
    }
    Tracks { tracks }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    fn unit(k: usize, n: usize) -> Vec<Complex> {
        (0..n).map(|i| (f64::from(u8::from(i == k)), 0.0)).collect()
    }

    /// The products' MAC table equals the pairwise definition (a zero vector included).
    #[test]
    fn mac_matrix_equals_the_pairwise_mac() {
        let vector = |seed: usize, d: usize| -> Vec<Complex> {
            (0..d)
                .map(|k| {
                    let x = (seed * 31 + k * 17) as f64;
                    ((0.37 * x).sin(), (0.11 * x + 1.0).cos())
                })
                .collect()
        };
        let d = 7;
        let previous: Vec<DenseEigenpair> =
            (0..5).map(|i| ((0.0, i as f64), vector(i, d))).collect();
        let mut next: Vec<DenseEigenpair> = (0..4)
            .map(|j| ((0.0, j as f64), vector(j + 9, d)))
            .collect();
        next[2].1 = vec![(0.0, 0.0); d];
        let table = mac_matrix(&previous, &next);
        for (i, p) in previous.iter().enumerate() {
            for (j, q) in next.iter().enumerate() {
                let (t, m) = (table[i + j * previous.len()], mac(&p.1, &q.1));
                assert!((t - m).abs() <= 1e-14, "({i}, {j}): {t} vs {m}");
            }
        }
    }

    #[test]
    fn mac_is_one_for_complex_multiples_and_zero_for_orthogonal() {
        let a = [(1.0, 0.5), (-0.3, 2.0)];
        let b: Vec<(f64, f64)> = a
            .iter()
            .map(|&(r, i)| (0.3 * r - 1.2 * i, 0.3 * i + 1.2 * r))
            .collect();
        assert!((mac(&a, &b) - 1.0).abs() < 1e-14);
        assert!(mac(&[(1.0, 0.0), (0.0, 0.0)], &[(0.0, 0.0), (0.0, 1.0)]) < 1e-30);
    }

    /// Two distinct modes whose frequencies cross (shapes e0 and e1 stay), and a doublet (e2,
    /// e3 plane) whose members rotate by 60 degrees per point while splitting slightly: the
    /// crossing is followed by shape, the doublet keeps its frequency order, no swaps.
    #[test]
    fn crossings_follow_shapes_and_doublets_do_not_swap() {
        let n = 4;
        let mut points = Vec::new();
        for p in 0..5 {
            let x = p as f64;
            let angle = (60.0 * x).to_radians();
            let (c, s) = (angle.cos(), angle.sin());
            let rotated = |a: f64, b: f64| -> Vec<Complex> {
                vec![(0.0, 0.0), (0.0, 0.0), (a, 0.0), (b, 0.0)]
            };
            let split = 1e-4 * (1.0 + x);
            points.push(vec![
                ((0.0, 100.0 + 10.0 * x), unit(0, n)), // rising
                ((0.0, 140.0 - 10.0 * x), unit(1, n)), // falling: crosses the first at x = 2
                ((0.0, 500.0 * (1.0 - split)), rotated(c, s)),
                ((0.0, 500.0 * (1.0 + split)), rotated(-s, c)),
            ]);
        }
        let t = track(&points);
        assert_eq!(t.tracks.len(), 4);
        for (k, track) in t.tracks.iter().enumerate() {
            let freqs: Vec<f64> = track.iter().map(|p| p.unwrap().0 .1).collect();
            match k {
                0 => assert!(freqs.windows(2).all(|w| w[1] > w[0]), "rising: {freqs:?}"),
                1 => assert!(freqs.windows(2).all(|w| w[1] < w[0]), "falling: {freqs:?}"),
                2 => assert!(
                    freqs.iter().all(|&f| f < 500.0),
                    "lower doublet member: {freqs:?}"
                ),
                _ => assert!(
                    freqs.iter().all(|&f| f > 500.0),
                    "upper doublet member: {freqs:?}"
                ),
            }
        }
    }

    /// The coalescence found on the brake's C35 (4.6 um, phase 11 of 32), in four shapes:
    /// the tracked pair has decoupled into a (e0) and b (e1); within the step a couples with
    /// a third mode c (e2) into a flutter pair whose halves are (e0 +- e2)/sqrt(2), each with
    /// MAC 1/2 to a. The pairing continues a by the stable half and b by itself; the pair
    /// tracked becomes the new flutter pair. Not when the members already form one, nor for
    /// a doublet, a mode split in frequency, or one that carries nothing of the member.
    #[test]
    fn a_member_coupling_with_a_third_mode_brings_its_flutter_partner_into_the_pair() {
        let n = 4;
        let half = |sign: f64| -> Vec<Complex> {
            let r = std::f64::consts::FRAC_1_SQRT_2;
            vec![(r, 0.0), (0.0, 0.0), (sign * r, 0.0), (0.0, 0.0)]
        };
        let previous = vec![
            ((-12.9, 17862.6), unit(0, n)),
            ((-13.2, 18247.3), unit(1, n)),
        ];
        let next = vec![
            ((-73.7, 17820.6), half(1.0)),
            ((-15.2, 18108.8), unit(1, n)),
            ((53.4, 17820.0), half(-1.0)),
            ((-9.0, 19300.0), unit(3, n)),
        ];
        let chosen: Vec<usize> = pair_modes(&previous, &next)
            .into_iter()
            .map(|c| c.unwrap().0)
            .collect();
        assert_eq!(chosen, vec![0, 1]);
        assert_eq!(coupling_pair(&previous, &next, &chosen), vec![0, 2]);
        // The tracked members are the flutter pair already: unchanged.
        let pair = vec![next[0].clone(), next[2].clone()];
        let mut with_copy = next.clone();
        with_copy.push(((60.0, 17820.3), half(-1.0)));
        assert_eq!(coupling_pair(&pair, &with_copy, &[0, 2]), vec![0, 2]);
        // A partner within the doublet spacing, split in frequency, or orthogonal: unchanged.
        for other in [(-73.6, 17820.5), (53.4, 17700.0)] {
            let mut modes = next.clone();
            modes[2].0 = other;
            assert_eq!(coupling_pair(&previous, &modes, &chosen), vec![0, 1]);
        }
        let mut orthogonal = next.clone();
        orthogonal[2].1 = unit(2, n);
        assert_eq!(coupling_pair(&previous, &orthogonal, &chosen), vec![0, 1]);
    }

    /// A 40-mode flutter chain, perturbed from one point to the next by a growing change of
    /// its coupling: the pairing of the tracked pair among the eigenpairs computed from all
    /// eigenvalues is the pairing among the full dense solve's (the same eigenvalues to
    /// 1e-10, MAC 1 to 1e-10), with vectors computed for fewer eigenvalues than all.
    #[test]
    fn pairing_from_all_eigenvalues_is_the_full_solves() {
        let m = 40;
        let chain = |mu: f64| {
            let (mut k, mut c) = (vec![0.0; m * m], vec![0.0; m * m]);
            for i in 0..m {
                let w = 1e3 * ((i / 2 + 1) as f64 + 0.01 * (i % 2) as f64);
                k[i * m + i] = w * w;
                c[i * m + i] = 2.0 * 0.005 * w;
                if i + 1 < m {
                    k[(i + 1) * m + i] = mu * w * w;
                    k[i * m + i + 1] = -mu * w * w;
                }
            }
            (k, c)
        };
        let (k0, c0) = chain(0.2);
        let nominal = solve_dense(m, &k0, &c0).unwrap();
        let least = (0..nominal.len())
            .min_by(|&a, &b| nominal[a].0 .0.total_cmp(&nominal[b].0 .0).reverse())
            .unwrap();
        let current = vec![nominal[least].clone()];
        let mut fewer = 0;
        for mu in [0.2001, 0.21, 0.3, 0.6] {
            let (k, c) = chain(mu);
            let full = solve_dense(m, &k, &c).unwrap();
            let subset = pairs_from_all_eigenvalues(m, &k, &c, &current).unwrap();
            fewer += usize::from(subset.len() < full.len());
            let a = pair_modes(&current, &full)[0].expect("paired in the full solve");
            let b = pair_modes(&current, &subset)[0].expect("paired in the subset");
            let (sa, sb) = (full[a.0].0, subset[b.0].0);
            let d = (sa.0 - sb.0).hypot(sa.1 - sb.1) / sa.0.hypot(sa.1);
            assert!(d <= 1e-10, "mu {mu}: {sa:?} vs {sb:?}");
            assert!(
                (a.1 - b.1).abs() <= 1e-10,
                "mu {mu}: MAC {} vs {}",
                a.1,
                b.1
            );
        }
        assert!(
            fewer >= 2,
            "vectors for fewer than all eigenvalues at {fewer} of 4"
        );
    }
}
