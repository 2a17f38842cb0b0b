//! Groups of ranks inside one run (`squeal run --groups G`): the ranks split into G groups,
//! each with its own PETSc session and its own copy of the model, each computing a block of
//! the noise matrix' points into `<output>/group-g-of-G`; rank 0 then merges the groups'
//! journals into `<output>`. For small models whose solves do not scale over ranks: 2 groups
//! of 1 rank do twice the points of 1 group of 2 (benches/matrix-results.md).

use std::path::{Path, PathBuf};

use crate::matrix::sample::Slice;
use crate::scene::Scene;

/// The group (from 0) of `rank` among `size` ranks in `groups` groups of consecutive ranks.
pub fn group_of(rank: usize, size: usize, groups: usize) -> usize {
    rank * groups / size
}

/// The points group `g` of `groups` computes of the run's `slice`: the slice's block split in
/// `groups` consecutive blocks (slice (K-1) G + g + 1 of N G: the union over the groups is
/// exactly slice K of N).
pub fn group_slice(slice: Slice, g: usize, groups: usize) -> Slice {
    Slice {
        index: (slice.index - 1) * groups + g + 1,
        count: slice.count * groups,
    }
}

/// Where group `g` writes.
pub fn group_dir(output: &Path, g: usize, groups: usize) -> PathBuf {
    output.join(format!("group-{}-of-{groups}", g + 1))
}

/// Why a scene or a rank count does not run in groups (None: it does).
pub fn refusal(scene: &Scene, groups: usize, size: usize) -> Option<String> {
    if groups > size {
        return Some(format!(
            "--groups {groups}: more groups than the {size} ranks"
        ));
    }
    if scene.matrix.is_none() {
        return Some(format!("--groups {groups}: groups compute the points of a noise matrix: the scene has no [matrix]"));
    }
    if scene.transient.is_some() || scene.sweep.is_some() || scene.post.is_some() {
        return Some(format!("--groups {groups}: a scene run in groups may hold the matrix and the stages it needs, not [transient], [sweep] or [post] (every group would repeat them)"));
    }
    None
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn groups_split_ranks_and_slices_consistently() {
        let groups: Vec<usize> = (0..5).map(|r| group_of(r, 5, 2)).collect();
        assert_eq!(groups, vec![0, 0, 0, 1, 1]);
        // The groups' blocks of slice 2/3 of 100 points are exactly that slice's block.
        let slice = Slice { index: 2, count: 3 };
        let mut covered = Vec::new();
        for g in 0..4 {
            covered.extend(group_slice(slice, g, 4).range(100));
        }
        assert_eq!(covered, slice.range(100).collect::<Vec<_>>());
    }
}
