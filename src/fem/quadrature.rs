//! Quadrature rules on the reference elements.

/// Gauss-Legendre points and weights on [-1, 1] with `n` points (exact to degree 2n-1).
pub fn gauss_legendre(n: usize) -> (&'static [f64], &'static [f64]) {
    const P1: [f64; 1] = [0.0];
    const W1: [f64; 1] = [2.0];
    const P2: [f64; 2] = [-0.577_350_269_189_625_8, 0.577_350_269_189_625_8];
    const W2: [f64; 2] = [1.0, 1.0];
    const P3: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
    const W3: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    const P4: [f64; 4] = [
        -0.861_136_311_594_052_6,
        -0.339_981_043_584_856_3,
        0.339_981_043_584_856_3,
        0.861_136_311_594_052_6,
    ];
    const W4: [f64; 4] = [
        0.347_854_845_137_453_9,
        0.652_145_154_862_546_1,
        0.652_145_154_862_546_1,
        0.347_854_845_137_453_9,
    ];
    match n {
        1 => (&P1, &W1),
        2 => (&P2, &W2),
        3 => (&P3, &W3),
        4 => (&P4, &W4),
        _ => panic!("Gauss-Legendre rule with {n} points is not tabulated (1-4)"),
    }
}

/// A quadrature rule: reference points and weights.
#[derive(Debug, Clone)]
pub struct Rule {
    pub points: Vec<[f64; 3]>,
    pub weights: Vec<f64>,
}

/// Tensor-product Gauss rule on the cube [-1, 1]^3 with n points per direction.
pub fn hex_rule(n: usize) -> Rule {
    let (p, w) = gauss_legendre(n);
    let mut rule = Rule {
        points: Vec::with_capacity(n * n * n),
        weights: Vec::with_capacity(n * n * n),
    };
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                rule.points.push([p[i], p[j], p[k]]);
                rule.weights.push(w[i] * w[j] * w[k]);
            }
        }
    }
    rule
}

/// Rule on the unit tetrahedron {x, y, z >= 0, x + y + z <= 1}, by the collapsed-cube
/// (Duffy) map x = u, y = v (1 - u), z = w (1 - u)(1 - v) with Jacobian (1 - u)^2 (1 - v) and
/// n Gauss points per direction on [0, 1]^3. A polynomial of degree p becomes one of degree
/// p + 2 in u, so n points integrate degree 2n - 3 exactly (n = 3: degree 3, n = 4: degree 5).
/// The symmetric 4-point rule on the unit tetrahedron, exact to degree 2 (the rule of Abaqus'
/// and CalculiX' C3D10).
pub fn tet_rule_4_points() -> Rule {
    let a = 0.585_410_196_624_968_5;
    let b = 0.138_196_601_125_010_5;
    Rule {
        points: vec![[b, b, b], [a, b, b], [b, a, b], [b, b, a]],
        weights: vec![1.0 / 24.0; 4],
    }
}

pub fn tet_rule(n: usize) -> Rule {
    let (p, w) = gauss_legendre(n);
    let map = |t: f64| 0.5 * (t + 1.0);
    let mut rule = Rule {
        points: Vec::with_capacity(n * n * n),
        weights: Vec::with_capacity(n * n * n),
    };
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let (u, v, s) = (map(p[i]), map(p[j]), map(p[k]));
                let x = u;
                let y = v * (1.0 - u);
                let z = s * (1.0 - u) * (1.0 - v);
                let jac = (1.0 - u) * (1.0 - u) * (1.0 - v);
                rule.points.push([x, y, z]);
                rule.weights.push(w[i] * w[j] * w[k] * 0.125 * jac);
            }
        }
    }
    rule
}

/// Product rule on the reference wedge (triangle 0 <= xi, eta, xi + eta <= 1 times zeta in
/// [-1, 1]): the triangle's centroid (1 point) or its interior 3-point rule (points at
/// (1/6, 1/6), (2/3, 1/6), (1/6, 2/3); exact to degree 2) times `line` Gauss points.
pub fn wedge_rule(triangle: usize, line: usize) -> Rule {
    let tri: Vec<([f64; 2], f64)> = match triangle {
        1 => vec![([1.0 / 3.0, 1.0 / 3.0], 0.5)],
        3 => vec![
            ([1.0 / 6.0, 1.0 / 6.0], 1.0 / 6.0),
            ([2.0 / 3.0, 1.0 / 6.0], 1.0 / 6.0),
            ([1.0 / 6.0, 2.0 / 3.0], 1.0 / 6.0),
        ],
        _ => panic!("wedge rule with {triangle} triangle points is not tabulated (1 or 3)"),
    };
    let (zp, zw) = gauss_legendre(line);
    let mut rule = Rule {
        points: Vec::new(),
        weights: Vec::new(),
    };
    for (z, wz) in zp.iter().zip(zw) {
        for (t, wt) in &tri {
            rule.points.push([t[0], t[1], *z]);
            rule.weights.push(wt * wz);
        }
    }
    rule
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn tet_rule_integrates_monomials_exactly() {
        // Integral of x^a y^b z^c over the unit tetrahedron = a! b! c! / (a + b + c + 3)!
        let fact = |n: u32| (1..=n).map(f64::from).product::<f64>();
        let rule = tet_rule(4);
        for (a, b, c) in [
            (0, 0, 0),
            (1, 0, 0),
            (2, 1, 0),
            (1, 1, 1),
            (4, 0, 1),
            (2, 2, 1),
        ] {
            let exact = fact(a) * fact(b) * fact(c) / fact(a + b + c + 3);
            let num: f64 = rule
                .points
                .iter()
                .zip(&rule.weights)
                .map(|(p, w)| w * p[0].powi(a as i32) * p[1].powi(b as i32) * p[2].powi(c as i32))
                .sum();
            assert!(
                (num - exact).abs() < 1e-14,
                "x^{a} y^{b} z^{c}: {num} vs {exact}"
            );
        }
    }

    #[test]
    fn hex_rule_integrates_degree_2n_minus_1() {
        let rule = hex_rule(3);
        let num: f64 = rule
            .points
            .iter()
            .zip(&rule.weights)
            .map(|(p, w)| w * p[0].powi(4) * p[1].powi(2) * (1.0 + p[2].powi(5)))
            .sum();
        assert!((num - (2.0 / 5.0) * (2.0 / 3.0) * 2.0).abs() < 1e-14);
    }
}
