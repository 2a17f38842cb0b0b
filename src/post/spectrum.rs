//! Spectra of time signals: power spectra (rustfft) and the spectrogram (short-time Fourier transform
//! with a Hann window) of a signal, resampled onto a uniform grid first when step cuts made
//! its steps uneven.

use crate::measure::nan_max;
use std::f64::consts::PI;

use rustfft::num_complex::Complex;

/// |X_k|^2 of the discrete Fourier transform of real samples (any length, rustfft), for
/// k = 0..=n/2.
pub fn power_spectrum(samples: &[f64]) -> Vec<f64> {
    let n = samples.len();
    if n == 0 {
        return Vec::new();
    }
    let fft = rustfft::FftPlanner::<f64>::new().plan_fft_forward(n);
    let mut buffer: Vec<Complex<f64>> = samples.iter().map(|&v| Complex::new(v, 0.0)).collect();
    fft.process(&mut buffer);
    buffer[..=n / 2].iter().map(|c| c.norm_sqr()).collect()
}

/// Linear interpolation of (t, y) onto t0 + k dt, k = 0..n.
pub fn resample(t: &[f64], y: &[f64], dt: f64) -> Vec<f64> {
    if t.len() < 2 {
        return y.to_vec();
    }
    let n = ((t[t.len() - 1] - t[0]) / dt).floor() as usize + 1;
    let mut out = Vec::with_capacity(n);
    let mut j = 0;
    for k in 0..n {
        let tk = t[0] + k as f64 * dt;
        while j + 2 < t.len() && t[j + 1] < tk {
            j += 1;
        }
        let (t0, t1) = (t[j], t[j + 1]);
        let s = if t1 > t0 {
            ((tk - t0) / (t1 - t0)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(y[j] + s * (y[j + 1] - y[j]));
    }
    out
}

/// A spectrogram: power spectral density (|X|^2 of Hann-windowed, mean-removed segments) per
/// segment (column) and frequency bin (row), column-major.
pub struct Spectrogram {
    /// Segment centres (s) and bin frequencies (Hz).
    pub times: Vec<f64>,
    pub frequencies: Vec<f64>,
    pub power: Vec<f64>,
}

/// Spectrogram of a uniformly sampled signal (step `dt`, first sample at `t0`) with segments of
/// `window` samples advanced by `hop`.
pub fn spectrogram(y: &[f64], t0: f64, dt: f64, window: usize, hop: usize) -> Spectrogram {
    assert!(window > 1 && hop > 0);
    let bins = window / 2 + 1;
    let hann: Vec<f64> = (0..window)
        .map(|i| 0.5 - 0.5 * (2.0 * PI * i as f64 / window as f64).cos())
        .collect();
    let mut out = Spectrogram {
        times: Vec::new(),
        frequencies: (0..bins).map(|k| k as f64 / (window as f64 * dt)).collect(),
        power: Vec::new(),
    };
    let mut start = 0;
    while start + window <= y.len() {
        let seg = &y[start..start + window];
        let mean = seg.iter().sum::<f64>() / window as f64;
        let windowed: Vec<f64> = seg.iter().zip(&hann).map(|(v, w)| (v - mean) * w).collect();
        out.power.extend(power_spectrum(&windowed));
        out.times
            .push(t0 + (start as f64 + 0.5 * window as f64) * dt);
        start += hop;
    }
    out
}

/// The signal a transient's spectrogram shows: the sensor displacement component that moves
/// most, or the braking torque without sensors; with its label.
pub fn spectrogram_signal(tr: &crate::time::transient::Transient) -> (Vec<f64>, String) {
    let spread = |v: &[f64]| {
        let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
        v.iter().map(|x| (x - mean).powi(2)).sum::<f64>()
    };
    let mut best: Option<(f64, Vec<f64>, String)> = None;
    for (name, values) in tr.sensor_names.iter().zip(&tr.sensor_values) {
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            let c: Vec<f64> = values[0].iter().skip(k).step_by(3).copied().collect();
            let sp = spread(&c);
            if best.as_ref().is_none_or(|b| sp > b.0) {
                best = Some((sp, c, format!("{name} {axis} displacement")));
            }
        }
    }
    match best {
        Some((_, c, what)) => (c, what),
        None => (tr.braking_torque(), "braking torque".into()),
    }
}

/// A spectrogram in dB up to `max_hz`, ready to draw: `db` is columns (times) x rows
/// (frequencies), column-major.
pub struct SpectrogramDb {
    pub columns: usize,
    pub rows: usize,
    pub db: Vec<f64>,
    /// Centre of the first and last column (s), and the bin width (Hz).
    pub first_time: f64,
    pub last_time: f64,
    pub column_width: f64,
    pub bin_hz: f64,
    pub top_db: f64,
}

/// The spectrogram of a transient's signal `y` at times `t`, on the nominal step grid `dt`
/// (Hann windows of about a quarter of the run, a power of two; 1/8 hop); None when the run is
/// too short for one.
pub fn spectrogram_db(t: &[f64], y: &[f64], dt: f64, max_hz: f64) -> Option<SpectrogramDb> {
    let uniform = resample(t, y, dt);
    let window = (uniform.len() / 4).clamp(64, 4096).next_power_of_two() / 2;
    if uniform.len() < 2 * window || window < 32 {
        return None;
    }
    let s = spectrogram(&uniform, t[0], dt, window, window / 8);
    let rows = s
        .frequencies
        .iter()
        .take_while(|&&f| f <= max_hz)
        .count()
        .max(2);
    let bins = s.frequencies.len();
    let columns = s.times.len();
    let mut db = Vec::with_capacity(columns * rows);
    for c in 0..columns {
        db.extend(
            s.power[c * bins..c * bins + rows]
                .iter()
                .map(|p| 10.0 * p.max(1e-300).log10()),
        );
    }
    let top_db = db.iter().copied().fold(f64::NEG_INFINITY, nan_max);
    Some(SpectrogramDb {
        columns,
        rows,
        db,
        first_time: s.times[0],
        last_time: s.times[columns - 1],
        column_width: s.times.get(1).map_or(1.0, |x| x - s.times[0]),
        bin_hz: s.frequencies[1],
        top_db,
    })
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn power_spectrum_equals_the_direct_transform_at_any_length() {
        for n in [60, 64, 97] {
            let x: Vec<f64> = (0..n)
                .map(|i| ((i * i) as f64 * 0.37).sin() + 0.1 * i as f64)
                .collect();
            let power = power_spectrum(&x);
            assert_eq!(power.len(), n / 2 + 1);
            for (k, p) in power.iter().enumerate() {
                let (mut a, mut b) = (0.0, 0.0);
                for (j, v) in x.iter().enumerate() {
                    let phase = -2.0 * PI * (j * k) as f64 / n as f64;
                    a += v * phase.cos();
                    b += v * phase.sin();
                }
                let direct = a * a + b * b;
                assert!(
                    (p - direct).abs() <= 1e-10 * crate::measure::nan_max(direct, 1.0),
                    "n {n} bin {k}"
                );
            }
        }
    }

    #[test]
    fn spectrogram_peak_follows_a_frequency_step_and_resampling_is_exact_on_lines() {
        // 4 kHz then 10 kHz, sampled at 1 MHz.
        let dt = 1e-6;
        let y: Vec<f64> = (0..8192)
            .map(|i| {
                let t = i as f64 * dt;
                let f = if i < 4096 { 4000.0 } else { 10000.0 };
                (2.0 * PI * f * t).sin()
            })
            .collect();
        let s = spectrogram(&y, 0.0, dt, 1024, 512);
        let bins = s.frequencies.len();
        let peak = |col: usize| {
            let p = &s.power[col * bins..(col + 1) * bins];
            let k = (0..bins).max_by(|&a, &b| p[a].total_cmp(&p[b])).unwrap();
            s.frequencies[k]
        };
        let df = s.frequencies[1];
        assert!((peak(0) - 4000.0).abs() <= df, "{}", peak(0));
        assert!((peak(s.times.len() - 1) - 10000.0).abs() <= df);
        let t = [0.0, 1.0, 3.0];
        let r = resample(&t, &[1.0, 2.0, 4.0], 0.5);
        assert_eq!(r, vec![1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0]);
    }
}
