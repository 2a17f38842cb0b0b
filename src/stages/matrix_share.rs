//! A noise-matrix point's dense complex modes, solved on one rank of the group, shared with
//! the others, and why a point fails.

use mpi::topology::SimpleCommunicator;

use crate::eigen::complex_modes::DenseEigenpair;
use crate::la::DenseError;
use crate::parallel::{broadcast_f64s, broadcast_string};
use crate::statics::StaticError;

/// Why a point of the matrix has no result. The matrix records it (as its text) and goes on.
#[derive(Debug, thiserror::Error)]
pub(super) enum PointFailure {
    /// A (nearly) singular tangent at the point's own load and laws, from the neighbour's
    /// state: not retried from the unloaded state (see `solve_static`).
    #[error("static state: from the nearest point: {0}; not retried from the unloaded state (to check it, run this point as a scene of its own)")]
    SingularFromNeighbour(Box<StaticError>),
    #[error("static state: from the nearest point: {warm}; from the unloaded state: {cold}")]
    NoStaticState {
        warm: Box<StaticError>,
        cold: Box<StaticError>,
    },
    #[error("complex modes: {0}")]
    ComplexModes(DenseError),
    #[error("complex modes: an eigenvalue is not finite (NaN or Inf)")]
    NotFinite,
    /// The failure of the rank that solved the dense modes, as that rank gave it.
    #[error("{0}")]
    OnSolvingRank(String),
}

/// What `root` found (`local` on that rank: the eigenpairs with m coordinates each and the
/// seconds they took, or why they failed), on every rank.
///
/// # Collective
pub(super) fn share_dense(
    comm: &SimpleCommunicator,
    root: usize,
    local: Option<Result<(Vec<DenseEigenpair>, f64), PointFailure>>,
    m: usize,
) -> Result<(Vec<DenseEigenpair>, f64), PointFailure> {
    let root = root as i32;
    // [1, seconds, then per pair Re(s), Im(s) and m coordinates (Re, Im)], or [0] and a message.
    let (mut data, mut message, own_failure) = match local {
        Some(Ok((pairs, seconds))) => (encode(&pairs, seconds, m), String::new(), None),
        Some(Err(failure)) => (vec![0.0], failure.to_string(), Some(failure)),
        None => (Vec::new(), String::new(), None),
    };
    broadcast_f64s(comm, root, &mut data);
    if data.first() != Some(&1.0) {
        broadcast_string(comm, root, &mut message);
        return Err(own_failure.unwrap_or(PointFailure::OnSolvingRank(message)));
    }
    Ok(decode(&data, m))
}

fn encode(pairs: &[DenseEigenpair], seconds: f64, m: usize) -> Vec<f64> {
    let mut data = Vec::with_capacity(2 + pairs.len() * (2 + 2 * m));
    data.extend([1.0, seconds]);
    for (s, y) in pairs {
        assert_eq!(y.len(), m, "coordinates of a dense eigenpair");
        data.extend([s.0, s.1]);
        data.extend(y.iter().flat_map(|&(re, im)| [re, im]));
    }
    data
}

fn decode(data: &[f64], m: usize) -> (Vec<DenseEigenpair>, f64) {
    let pairs = data[2..]
        .chunks_exact(2 + 2 * m)
        .map(|c| {
            let y = c[2..].chunks_exact(2).map(|z| (z[0], z[1])).collect();
            ((c[0], c[1]), y)
        })
        .collect();
    (pairs, data[1])
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn eigenpairs_survive_the_encoding_bit_for_bit() {
        let pairs: Vec<DenseEigenpair> = vec![
            ((-1.5, 2.0e4), vec![(1.0, -0.0), (f64::MIN_POSITIVE, 3.0)]),
            ((7.0, 0.0), vec![(-2.0, 1e-300), (0.25, f64::MAX)]),
        ];
        let (back, seconds) = decode(&encode(&pairs, 0.125, 2), 2);
        assert_eq!(seconds, 0.125);
        assert_eq!(back.len(), 2);
        for (a, b) in pairs.iter().zip(&back) {
            assert_eq!(a.0 .0.to_bits(), b.0 .0.to_bits());
            assert_eq!(a.0 .1.to_bits(), b.0 .1.to_bits());
            for (x, y) in a.1.iter().zip(&b.1) {
                assert_eq!(
                    (x.0.to_bits(), x.1.to_bits()),
                    (y.0.to_bits(), y.1.to_bits())
                );
            }
        }
    }
}
