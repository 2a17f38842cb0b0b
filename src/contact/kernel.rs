//! The contact point kernel: from the observed gap, relative tangential displacements and
//! sliding speed of one point to its tractions, and the point's contributions to the force
//! vector and the tangent matrices. Pure Rust, so every tangent is tested against finite
//! differences of the force without MPI.

use super::law::{FrictionLaw, NormalLaw};

/// The rows of the observation matrices at one point, dense over the point's DOFs (master
/// nodes then slave nodes, 3 per node; -1 marks an eliminated DOF).
#[derive(Debug, Clone, Default)]
pub struct PointRows {
    pub dofs: Vec<i32>,
    pub nor: Vec<f64>,
    pub tan: Vec<f64>,
    pub tan2: Vec<f64>,
    pub conv: Vec<f64>,
}

/// What the observation matrices see at one point.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Observed {
    pub gap: f64,
    /// Relative tangential displacements (slave minus master) along the two tangents.
    pub slip: [f64; 2],
    /// Sliding speed of the disc under the pad along the tangent (m/s).
    pub speed: f64,
}

/// Contact status of a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    Open = 0,
    Stick = 1,
    Slip = 2,
}

/// The response of one point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointResponse {
    pub pressure: f64,
    pub stiffness: f64,
    /// Tangential tractions on the master along the two tangents (Pa).
    pub traction: [f64; 2],
    pub status: Status,
    // Derivatives, for the tangents.
    stiffness_slope: f64,
    d_pressure: f64,
    d_speed: f64,
    stick: f64,
    /// The joints' dt/d delta and dt/dg.
    stick_slip: [[f64; 2]; 2],
    stick_gap: [f64; 2],
}

impl PointResponse {
    /// A point of a sliding interface whose speed lies inside the friction law's
    /// regularization band (|w| < slip_speed): there the traction's slope in the speed is
    /// mu p / slip_speed, the stiffest term of the time integration.
    pub fn in_friction_band(&self) -> bool {
        self.status == Status::Stick && self.stick == 0.0
    }
}

/// The law pair of an interface applied at one point; `friction_scale` ramps the friction of
/// sliding interfaces in.
pub fn respond(
    normal: &NormalLaw,
    friction: &FrictionLaw,
    friction_scale: f64,
    o: Observed,
) -> PointResponse {
    let n = normal.eval(o.gap);
    let open = normal.is_open(o.gap);
    if friction.is_sliding() {
        let t = friction.traction(n.pressure, o.speed);
        PointResponse {
            pressure: n.pressure,
            stiffness: n.stiffness,
            traction: [friction_scale * t.traction, 0.0],
            status: if open {
                Status::Open
            } else if o.speed.abs() < friction.slip_speed() {
                Status::Stick
            } else {
                Status::Slip
            },
            stiffness_slope: n.stiffness_slope,
            d_pressure: friction_scale * t.d_pressure,
            d_speed: friction_scale * t.d_speed,
            stick: 0.0,
            stick_slip: [[0.0; 2]; 2],
            stick_gap: [0.0; 2],
        }
    } else {
        // Joints hold from the start: the friction ramp is for the sliding interfaces only.
        let t = friction.stick_traction(&n, o.slip);
        PointResponse {
            pressure: n.pressure,
            stiffness: n.stiffness,
            traction: t.traction,
            // A joint point slides once its traction is within 10 % of Coulomb's limit.
            status: if open {
                Status::Open
            } else if t.saturation > 0.9 {
                Status::Slip
            } else {
                Status::Stick
            },
            stiffness_slope: n.stiffness_slope,
            d_pressure: 0.0,
            d_speed: 0.0,
            stick: friction.stick_stiffness(),
            stick_slip: t.d_slip,
            stick_gap: t.d_gap,
        }
    }
}

/// Observes one point: gap = c_n . u + g0, slip = c_t . u, speed = c_t . v + omega (r +
/// c_conv . u).
pub fn observe(
    rows: &PointRows,
    g0: f64,
    omega_r: f64,
    omega: f64,
    u: &[f64],
    v: &[f64],
) -> Observed {
    let d = |a: &[f64], x: &[f64]| a.iter().zip(x).map(|(p, q)| p * q).sum::<f64>();
    Observed {
        gap: d(&rows.nor, u) + g0,
        slip: [d(&rows.tan, u), d(&rows.tan2, u)],
        speed: d(&rows.tan, v) + omega_r + omega * d(&rows.conv, u),
    }
}

/// The point's force on its DOFs, scaled by its weight: f = w (c_n p - c_t t1 - c_t2 t2).
pub fn force(rows: &PointRows, weight: f64, r: &PointResponse, out: &mut [f64]) {
    for i in 0..rows.dofs.len() {
        out[i] = weight
            * (rows.nor[i] * r.pressure
                - rows.tan[i] * r.traction[0]
                - rows.tan2[i] * r.traction[1]);
    }
}

/// Which tangent matrix a contribution belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    /// K_c = C_NOR^T diag(w k_c) C_NOR (symmetric).
    Normal,
    /// K_stick = C_TAN^T diag(w dt/d delta) C_TAN over both stick directions (symmetric;
    /// w mu k_c at small slip).
    Stick,
    /// K_f: friction of sliding points (unsymmetric).
    Friction,
    /// The joints' traction depends on the gap (through p and k_c): its consistent tangent
    /// couples slip rows to normal columns (unsymmetric, non-conservative: a source of
    /// mode-coupling instability like the pads' friction), in the Newton solvers and the
    /// complex modes alike.
    StickCoupling,
    /// C_f = C_TAN^T diag(w dt/dw) C_TAN, the friction damping (where the law has a slope).
    Damping,
}

/// One of the observation rows of a point (the channels a tangent couples).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    Nor = 0,
    Tan = 1,
    Tan2 = 2,
    Conv = 3,
}

impl PointRows {
    pub fn row(&self, c: Channel) -> &[f64] {
        match c {
            Channel::Nor => &self.nor,
            Channel::Tan => &self.tan,
            Channel::Tan2 => &self.tan2,
            Channel::Conv => &self.conv,
        }
    }
}

/// The point's contribution of `part` as rank-one terms `coef c_a c_b^T` over its observation
/// rows: -d(force)/du for stiffness parts, -d(force)/dv for damping. The one definition both
/// the sparse tangents (over DOFs) and the projected ones (over modal coordinates) use.
pub fn tangent_terms(
    weight: f64,
    omega: f64,
    r: &PointResponse,
    part: Part,
) -> Vec<(f64, Channel, Channel)> {
    let mut terms = Vec::with_capacity(4);
    push_tangent_terms(weight, omega, r, part, 1.0, &mut terms);
    terms
}

/// [`tangent_terms`] times `scale`, appended to `out` (no allocation per point).
pub fn push_tangent_terms(
    weight: f64,
    omega: f64,
    r: &PointResponse,
    part: Part,
    scale: f64,
    out: &mut Vec<(f64, Channel, Channel)>,
) {
    use Channel::*;
    let w = scale * weight;
    let mut push = |c: f64, a: Channel, b: Channel| {
        if c != 0.0 {
            out.push((c, a, b));
        }
    };
    match part {
        Part::Normal => push(w * r.stiffness, Nor, Nor),
        Part::Stick => {
            let k = r.stick_slip.map(|row| row.map(|x| w * x));
            push(k[0][0], Tan, Tan);
            push(k[0][1], Tan, Tan2);
            push(k[1][0], Tan2, Tan);
            push(k[1][1], Tan2, Tan2);
        }
        Part::StickCoupling if r.stick != 0.0 => {
            // The joints' traction depends on the gap through p and k_c.
            let c = r.stick_gap.map(|x| w * x);
            push(c[0], Tan, Nor);
            push(c[1], Tan2, Nor);
        }
        Part::Friction if r.stick == 0.0 => {
            // t = T(p(g), w(u, v)): dp/dg = -k_c, dw/du = omega c_conv.
            push(-w * r.d_pressure * r.stiffness, Tan, Nor);
            push(w * r.d_speed * omega, Tan, Conv);
        }
        Part::Friction | Part::StickCoupling => {}
        Part::Damping => push(w * r.d_speed, Tan, Tan),
    }
}

/// Adds the point's contribution of `part` to a dense row-major |dofs| x |dofs| matrix.
pub fn add_tangent(
    rows: &PointRows,
    weight: f64,
    omega: f64,
    r: &PointResponse,
    part: Part,
    out: &mut [f64],
) {
    let n = rows.dofs.len();
    for (coef, a, b) in tangent_terms(weight, omega, r, part) {
        let (a, b) = (rows.row(a), rows.row(b));
        for i in 0..n {
            if a[i] == 0.0 {
                continue;
            }
            let ai = coef * a[i];
            for j in 0..n {
                out[i * n + j] += ai * b[j];
            }
        }
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;
    use crate::measure::nan_max;

    fn rows(n: usize, seed: u64) -> PointRows {
        let mut s = seed;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        PointRows {
            dofs: (0..n as i32).collect(),
            nor: (0..n).map(|_| rnd()).collect(),
            tan: (0..n).map(|_| rnd()).collect(),
            tan2: (0..n).map(|_| rnd()).collect(),
            conv: (0..n).map(|_| rnd() * 10.0).collect(),
        }
    }

    /// -df/du and -df/dv of the point force against central differences, relative error below
    /// 1e-6, for each law: at ordinary states, at the exponential guard, deep penetration, and
    /// sliding speeds near and across zero.
    #[test]
    fn point_tangents_match_central_differences() {
        let exp = NormalLaw::Exponential {
            p0: 1e6,
            lambda: 2e5,
            linear_below_gap: None,
        };
        let g_lin = exp.guard_gap().unwrap();
        let lin = NormalLaw::Linear { stiffness: 3e11 };
        let [coulomb, arctan, stribeck] = crate::contact::law::sample_sliding_laws(0.2);
        let frictions = [coulomb, arctan, stribeck, FrictionLaw::Stick { mu: 0.2 }];
        let n = 12;
        let rows = rows(n, 7);
        let (weight, omega) = (2.5e-5, 6.0);
        // (g0, omega r, displacement scale): ordinary, at the guard, deep, near-zero speed.
        let cases = [
            (2e-6, 0.9, 1e-6),
            (g_lin, 0.5, 1e-7),
            (-1e-3, 0.7, 1e-6),
            (1e-6, 2e-4, 1e-6),
            (1e-6, 0.0, 1e-6),
            // Slips of ~1e-5 m: the joints' traction near Coulomb's limit (lambda |delta| ~ 2).
            (1e-6, 0.9, 1e-4),
        ];
        for normal in [exp, lin] {
            for friction in frictions {
                for &(g0, omega_r, scale) in &cases {
                    let u: Vec<f64> = (0..n)
                        .map(|i| scale * ((i as f64) * 0.37).sin() * 0.1)
                        .collect();
                    let v: Vec<f64> = (0..n).map(|i| 1e-4 * ((i as f64) * 0.61).cos()).collect();
                    let eval = |u: &[f64], v: &[f64]| {
                        let o = observe(&rows, g0, omega_r, omega, u, v);
                        let r = respond(&normal, &friction, 1.0, o);
                        let mut f = vec![0.0; n];
                        force(&rows, weight, &r, &mut f);
                        (o, r, f)
                    };
                    let (o, r, _) = eval(&u, &v);
                    let mut k = vec![0.0; n * n];
                    let mut c = vec![0.0; n * n];
                    for part in [
                        Part::Normal,
                        Part::Stick,
                        Part::Friction,
                        Part::StickCoupling,
                    ] {
                        add_tangent(&rows, weight, omega, &r, part, &mut k);
                    }
                    add_tangent(&rows, weight, omega, &r, Part::Damping, &mut c);
                    // Steps relative to the state, so round-off stays below the truncation error.
                    let hv = 1e-5 * crate::measure::nan_max(o.speed.abs(), 1e-3);
                    for (what, matrix, h) in [("stiffness", &k, 1e-11), ("damping", &c, hv)] {
                        let mut fd = vec![0.0; n * n];
                        for j in 0..n {
                            let (mut up, mut um, mut vp, mut vm) =
                                (u.clone(), u.clone(), v.clone(), v.clone());
                            if what == "stiffness" {
                                up[j] += h;
                                um[j] -= h;
                            } else {
                                vp[j] += h;
                                vm[j] -= h;
                            }
                            let (fp, fm) = (eval(&up, &vp).2, eval(&um, &vm).2);
                            for i in 0..n {
                                fd[i * n + j] = -(fp[i] - fm[i]) / (2.0 * h);
                            }
                        }
                        let scale = matrix
                            .iter()
                            .chain(&fd)
                            .fold(0.0f64, |m, x| nan_max(m, x.abs()));
                        let err = matrix
                            .iter()
                            .zip(&fd)
                            .fold(0.0f64, |m, (a, b)| nan_max(m, (a - b).abs()));
                        // The linear law's kink and Coulomb's slip-speed kink are not
                        // differentiable: skip states sitting on them.
                        let on_kink =
                            matches!(normal, NormalLaw::Linear { .. }) && o.gap.abs() < 1e-9;
                        if scale > 0.0 && !on_kink {
                            assert!(
                                err <= 1e-6 * scale,
                                "{what}: {normal:?} {friction:?} g0 {g0} w {omega_r}: error {err:.3e} of {scale:.3e}"
                            );
                        }
                    }
                }
            }
        }
    }

    /// The three coupling topologies: normal couples normal DOFs to normal DOFs (symmetric),
    /// stick tangential to tangential (symmetric), slide tangential rows to normal columns
    /// (unsymmetric).
    #[test]
    fn matrix_topologies_of_normal_stick_and_slide() {
        // Two nodes along z, master above the slave: DOFs (x, y, z) of master then slave.
        let rows = PointRows {
            dofs: (0..6).collect(),
            nor: vec![0.0, 0.0, 1.0, 0.0, 0.0, -1.0],
            tan: vec![-1.0, 0.0, 0.0, 1.0, 0.0, 0.0],
            tan2: vec![0.0, -1.0, 0.0, 0.0, 1.0, 0.0],
            conv: vec![0.0; 6],
        };
        let law = NormalLaw::Linear { stiffness: 1.0 };
        let o = Observed {
            gap: -0.1,
            slip: [0.0, 0.0],
            speed: 1.0,
        };
        let pattern = |friction: FrictionLaw, part: Part| {
            let r = respond(&law, &friction, 1.0, o);
            let mut m = vec![0.0; 36];
            add_tangent(&rows, 1.0, 0.0, &r, part, &mut m);
            m
        };
        let nz = |m: &[f64]| -> Vec<(usize, usize)> {
            (0..36)
                .filter(|&k| m[k] != 0.0)
                .map(|k| (k / 6, k % 6))
                .collect()
        };
        let sym = |m: &[f64]| (0..6).all(|i| (0..6).all(|j| m[i * 6 + j] == m[j * 6 + i]));
        let kn = pattern(FrictionLaw::None, Part::Normal);
        assert_eq!(nz(&kn), vec![(2, 2), (2, 5), (5, 2), (5, 5)]);
        assert!(sym(&kn));
        let ks = pattern(FrictionLaw::Stick { mu: 0.3 }, Part::Stick);
        assert_eq!(
            nz(&ks),
            vec![
                (0, 0),
                (0, 3),
                (1, 1),
                (1, 4),
                (3, 0),
                (3, 3),
                (4, 1),
                (4, 4)
            ]
        );
        assert!(sym(&ks));
        let kf = pattern(
            FrictionLaw::Coulomb {
                mu: 0.3,
                slip_speed: 1e-3,
            },
            Part::Friction,
        );
        assert_eq!(nz(&kf), vec![(0, 2), (0, 5), (3, 2), (3, 5)]);
        assert!(!sym(&kf));
        // Sliding at +speed: the disc drags the pad along +t, more so when pressed harder.
        assert_eq!(kf[2], 0.3 * 1.0);
    }
}
