//! The transient's vibration on the mesh, for ParaView: the stored states of the run's last
//! periods, thinned to a stated number a period, each recovered on the full model (from the
//! reduced coordinates when the transient ran reduced) less the static state. Written as
//! nodal fields `/vibration/frame_NNNN` with their times in `/vibration/time`;
//! vibration.xdmf describes them as a time series.

use crate::fem::dofmap::DofMap;
use crate::io::results::{ResultsError, ResultsFile};

/// Which stored states became frames, and at what rate.
#[derive(Debug, Clone, PartialEq)]
pub struct Frames {
    /// Indices of the stored states, in time order.
    pub states: Vec<usize>,
    pub times: Vec<f64>,
    /// Every `stride`-th stored state.
    pub stride: usize,
    /// The vibration's period (s) and the frames in one.
    pub period: f64,
    pub per_period: f64,
}

impl Frames {
    /// The stored states (times `times`) of the last `periods` periods (`period`, s), every
    /// `stride`-th back from the last so that about `per_period` fall in a period. None when
    /// no frame is asked for or fewer than two frames would result.
    pub fn choose(times: &[f64], period: f64, periods: f64, per_period: usize) -> Option<Frames> {
        let last = *times.last()?;
        if periods <= 0.0 || !(period > 0.0 && period.is_finite()) || per_period == 0 {
            return None;
        }
        let from = last - periods * period;
        let window: Vec<usize> = (0..times.len()).filter(|&i| times[i] >= from).collect();
        if window.len() < 2 {
            return None;
        }
        let span = last - times[window[0]];
        let stored_per_period = (window.len() - 1) as f64 * period / span;
        let stride = ((stored_per_period / per_period as f64).floor() as usize).max(1);
        let mut states: Vec<usize> = window.iter().rev().step_by(stride).copied().collect();
        states.reverse();
        // A period longer than the run (no vibration found: the period stands in as 1e300 s)
        // leaves one frame: no film to show.
        if states.len() < 2 {
            return None;
        }
        Some(Frames {
            times: states.iter().map(|&i| times[i]).collect(),
            states,
            stride,
            period,
            per_period: stored_per_period / stride as f64,
        })
    }

    /// In words, for the summary: "97 frames from ... s to ... s (4.0 periods of ... s, 24.0
    /// frames a period: every 3rd stored state)".
    pub fn describe(&self) -> String {
        let first = self.times.first().copied().unwrap_or(0.0);
        let last = self.times.last().copied().unwrap_or(0.0);
        let every = match self.stride {
            1 => "every stored state".to_string(),
            n => format!("every {} stored state", ordinal(n)),
        };
        format!(
            "{} frames from {first:.4e} s to {last:.4e} s ({:.1} periods of {:.3e} s, {:.1} frames a period: {every})",
            self.times.len(),
            (last - first) / self.period,
            self.period,
            self.per_period,
        )
    }
}

fn ordinal(n: usize) -> String {
    let suffix = match (n % 10, n % 100) {
        (1, x) if x != 11 => "st",
        (2, x) if x != 12 => "nd",
        (3, x) if x != 13 => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}

/// Frame `k`: the vibration about the static state at the nodes (`local`: this rank's DOFs).
///
/// # Collective
pub fn write_frame(
    file: &ResultsFile,
    k: usize,
    dofs: &DofMap,
    local: &[f64],
) -> Result<(), ResultsError> {
    file.write_nodal(&crate::io::xdmf::frame_dataset(k)[1..], dofs, local, "m")
}

/// The frames' times and rate.
///
/// # Collective
pub fn write_times(file: &ResultsFile, frames: &Frames) -> Result<(), ResultsError> {
    file.write_table("vibration/time", &frames.times, "s")?;
    file.set_number("vibration", "stride", frames.stride as f64)?;
    file.set_number("vibration", "period_s", frames.period)?;
    file.set_number("vibration", "frames_per_period", frames.per_period)?;
    file.set_text(
        "vibration",
        "what",
        "displacement less the static state at the stored states of the last periods",
    )
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn frames_are_thinned_back_from_the_last_state() {
        // 10 stored states a period of 1 s, 3 periods asked, 5 frames a period: every 2nd.
        let times: Vec<f64> = (0..=100).map(|i| i as f64 * 0.1).collect();
        let f = Frames::choose(&times, 1.0, 3.0, 5).unwrap();
        assert_eq!(f.stride, 2);
        assert_eq!(*f.states.last().unwrap(), 100);
        assert_eq!(f.states.first(), Some(&70));
        assert_eq!(f.states.len(), 16);
        assert!((f.per_period - 5.0).abs() < 1e-12, "{}", f.per_period);
        assert!(f.times.windows(2).all(|w| w[1] > w[0]));
        assert!(
            f.describe().contains("every 2nd stored state"),
            "{}",
            f.describe()
        );
    }

    #[test]
    fn fewer_stored_states_than_asked_keeps_every_one() {
        let times: Vec<f64> = (0..=20).map(|i| i as f64 * 0.25).collect();
        let f = Frames::choose(&times, 1.0, 2.0, 24).unwrap();
        assert_eq!(f.stride, 1);
        assert_eq!(f.states, (12..=20).collect::<Vec<_>>());
    }

    #[test]
    fn no_frames_when_none_are_asked_or_the_period_is_unknown() {
        let times: Vec<f64> = (0..10).map(f64::from).collect();
        assert_eq!(Frames::choose(&times, 1.0, 0.0, 24), None);
        assert_eq!(Frames::choose(&times, f64::NAN, 4.0, 24), None);
        assert_eq!(Frames::choose(&[], 1.0, 4.0, 24), None);
        assert_eq!(Frames::choose(&times, 1e-6, 4.0, 24), None);
        // No vibration in the run: its stand-in period of 1e300 s gives no frames.
        assert_eq!(Frames::choose(&times, 1e300, 4.0, 24), None);
    }
}
