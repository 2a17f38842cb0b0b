//! The parametric disc brake of a passenger car's front axle: disc (friction ring + hat),
//! inner and outer pad (lining on backplate), piston, floating caliper and anchor bracket.
//! One file per component; `grid` is the meshing engine they share.
//!
//! Frame: the disc axis is z, the outboard side (hat, caliper fingers) is +z, the pads are
//! centred on the +x axis (theta = 0). Only the components a scene lists are built; the
//! boundary conditions of a missing neighbour are replaced by what it would impose (see
//! `generate`).

pub mod anchor;
pub mod caliper;
pub mod disc;
pub mod grid;
pub mod pad;
pub mod piston;

use crate::invalid::InvalidSetting;
use serde::{Deserialize, Serialize};

use crate::mesh::material::{Elasticity, Material};
use crate::mesh::Clamp;
use crate::mesh::ElementKind;
use crate::mesh::Mesh;
pub use crate::mesh::{Interface, InterfaceKind, PressureLoad};
use grid::{Grid, GridMesh};

/// Which cells of a grid belong to which block.
pub type Selector = Box<dyn Fn([usize; 3]) -> Option<usize>>;

/// Cells for a length at element size `h`, at least `min`.
pub fn cells(length: f64, h: f64, min: usize) -> usize {
    ((length / h).round() as usize).max(min)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Component {
    Disc,
    InnerPad,
    OuterPad,
    Piston,
    Caliper,
    Anchor,
}

impl Component {
    pub const ALL: [Component; 6] = [
        Component::Disc,
        Component::InnerPad,
        Component::OuterPad,
        Component::Piston,
        Component::Caliper,
        Component::Anchor,
    ];
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    Inner,
    Outer,
}

impl Side {
    pub fn name(self) -> &'static str {
        match self {
            Side::Inner => "inner",
            Side::Outer => "outer",
        }
    }
}

/// Dimensions in m, angles in degrees. Defaults: a 300 x 28 mm solid front disc with a
/// 54 mm single-piston floating caliper.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BrakeGeometry {
    pub disc_outer_radius: f64,
    pub disc_thickness: f64,
    /// Outer radius of the hat wall (where the friction ring begins).
    pub hat_radius: f64,
    pub hat_wall: f64,
    /// From the outboard friction face to the top of the hat flange.
    pub hat_height: f64,
    pub hat_flange: f64,
    pub center_bore_radius: f64,
    pub bolt_circle_radius: f64,
    pub pad_inner_radius: f64,
    pub pad_outer_radius: f64,
    /// Arc of the lining.
    pub pad_arc_deg: f64,
    pub lining_thickness: f64,
    pub backplate_thickness: f64,
    /// Radial overhang of the backplate beyond the lining.
    pub backplate_margin: f64,
    /// Angular length of each backplate ear beyond the lining.
    pub ear_deg: f64,
    pub piston_diameter: f64,
    pub piston_length: f64,
    pub piston_wall: f64,
    /// Radial gap between the disc rim and the caliper bridge.
    pub caliper_clearance: f64,
    /// Wall thickness of the caliper (housing back, bore wall, bridge, fingers).
    pub caliper_wall: f64,
}

impl Default for BrakeGeometry {
    fn default() -> Self {
        BrakeGeometry {
            disc_outer_radius: 0.150,
            disc_thickness: 0.028,
            hat_radius: 0.085,
            hat_wall: 0.006,
            hat_height: 0.045,
            hat_flange: 0.008,
            center_bore_radius: 0.035,
            bolt_circle_radius: 0.057,
            pad_inner_radius: 0.097,
            pad_outer_radius: 0.147,
            pad_arc_deg: 52.0,
            lining_thickness: 0.010,
            backplate_thickness: 0.0055,
            backplate_margin: 0.002,
            ear_deg: 4.0,
            piston_diameter: 0.054,
            piston_length: 0.030,
            piston_wall: 0.006,
            caliper_clearance: 0.005,
            caliper_wall: 0.010,
        }
    }
}

impl BrakeGeometry {
    /// Checks that every dimension is positive and that the components fit together; errors
    /// name the key under `model.geometry`.
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        let fields: [(&str, f64); 20] = [
            ("disc_outer_radius", self.disc_outer_radius),
            ("disc_thickness", self.disc_thickness),
            ("hat_radius", self.hat_radius),
            ("hat_wall", self.hat_wall),
            ("hat_height", self.hat_height),
            ("hat_flange", self.hat_flange),
            ("center_bore_radius", self.center_bore_radius),
            ("bolt_circle_radius", self.bolt_circle_radius),
            ("pad_inner_radius", self.pad_inner_radius),
            ("pad_outer_radius", self.pad_outer_radius),
            ("pad_arc_deg", self.pad_arc_deg),
            ("lining_thickness", self.lining_thickness),
            ("backplate_thickness", self.backplate_thickness),
            ("backplate_margin", self.backplate_margin),
            ("ear_deg", self.ear_deg),
            ("piston_diameter", self.piston_diameter),
            ("piston_length", self.piston_length),
            ("piston_wall", self.piston_wall),
            ("caliper_clearance", self.caliper_clearance),
            ("caliper_wall", self.caliper_wall),
        ];
        for (key, v) in fields {
            if !(v.is_finite() && v > 0.0) {
                return Err(InvalidSetting::new(
                    format!("model.geometry.{key}"),
                    format!(" = {v}: must be positive and finite (m, or degrees for *_deg)"),
                ));
            }
        }
        let fits = |ok: bool, what: &str| -> Result<(), InvalidSetting> {
            if ok {
                Ok(())
            } else {
                Err(InvalidSetting::new("model.geometry", format!(": {what}")))
            }
        };
        fits(
            self.center_bore_radius < self.bolt_circle_radius - disc::BOLT_HALF_WIDTH
                && self.bolt_circle_radius + disc::BOLT_HALF_WIDTH
                    < self.hat_radius - self.hat_wall,
            "the bolt circle (+-6 mm) must lie between center_bore_radius and the hat wall (hat_radius - hat_wall)",
        )?;
        fits(
            self.hat_height > self.hat_flange,
            "hat_height must exceed hat_flange",
        )?;
        fits(
            self.hat_radius < self.pad_inner_radius - self.backplate_margin
                && self.pad_inner_radius < self.pad_outer_radius
                && self.pad_outer_radius + self.backplate_margin <= self.disc_outer_radius,
            "need hat_radius < pad_inner_radius - backplate_margin < pad_outer_radius + backplate_margin <= disc_outer_radius",
        )?;
        fits(
            self.pad_arc_deg + 2.0 * self.ear_deg < 150.0,
            "pad_arc_deg + 2 ear_deg must stay below 150 degrees",
        )?;
        fits(
            2.0 * self.piston_wall < self.piston_diameter / 2.0 - piston::VENT_RADIUS
                && self.piston_wall < self.piston_length,
            "piston_wall is too thick for piston_diameter / piston_length",
        )?;
        let (r, theta, _) = caliper::breaks(self);
        fits(
            r.windows(2).all(|w| w[0] < w[1]) && theta.windows(2).all(|w| w[0] < w[1]),
            "the caliper does not fit: the piston bore (piston_diameter + 4 mm) must lie within the pad's radial band and arc, below disc_outer_radius + caliper_clearance",
        )?;
        let (r, _, _) = anchor::breaks(self);
        fits(
            r[0] > 0.0 && r.windows(2).all(|w| w[0] < w[1]),
            "the anchor does not fit below the caliper housing: increase pad_inner_radius or reduce piston_diameter",
        )?;
        Ok(())
    }
}

/// Materials of the components. Defaults: grey cast iron disc, transversely isotropic
/// organic lining (soft through its thickness, z), steel backplates and piston, nodular cast
/// iron caliper and anchor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BrakeMaterials {
    pub disc: Material,
    pub lining: Material,
    pub backplate: Material,
    pub piston: Material,
    pub caliper: Material,
    pub anchor: Material,
}

impl Default for BrakeMaterials {
    fn default() -> Self {
        let nodular = Material::isotropic("nodular cast iron", 1.7e11, 0.28, 7100.0);
        BrakeMaterials {
            disc: Material::isotropic("grey cast iron", 1.1e11, 0.26, 7200.0),
            lining: Material {
                name: "pad lining".into(),
                density: 2500.0,
                elasticity: Elasticity::Orthotropic {
                    e1: 6e9,
                    e2: 6e9,
                    e3: 2e9,
                    nu12: 0.25,
                    nu13: 0.1,
                    nu23: 0.1,
                    g12: 2.4e9,
                    g13: 1.0e9,
                    g23: 1.0e9,
                },
            },
            backplate: Material::isotropic("steel", 2.1e11, 0.3, 7850.0),
            piston: Material::isotropic("steel", 2.1e11, 0.3, 7850.0),
            caliper: nodular.clone(),
            anchor: nodular,
        }
    }
}

fn all_components() -> Vec<Component> {
    Component::ALL.to_vec()
}

fn default_element() -> ElementKind {
    ElementKind::Hex8I
}

fn default_target_dofs() -> usize {
    30_000
}

fn default_pressure() -> f64 {
    20.0
}

/// The `[model]` table of a scene with `source = "brake"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrakeSpec {
    /// What to build: any of disc, inner_pad, outer_pad, piston, caliper, anchor.
    #[serde(default = "all_components")]
    pub components: Vec<Component>,
    /// hex8i (default) or hex20.
    #[serde(default = "default_element")]
    pub element: ElementKind,
    /// Size of the model in degrees of freedom; the generator hits it within 10 %.
    #[serde(default = "default_target_dofs")]
    pub target_dofs: usize,
    /// Brake-line pressure (bar) on the piston bottom and the caliper bore.
    #[serde(default = "default_pressure")]
    pub pressure_bar: f64,
    #[serde(default)]
    pub geometry: BrakeGeometry,
    #[serde(default)]
    pub materials: BrakeMaterials,
}

impl Default for BrakeSpec {
    fn default() -> Self {
        BrakeSpec {
            components: all_components(),
            element: default_element(),
            target_dofs: default_target_dofs(),
            pressure_bar: default_pressure(),
            geometry: BrakeGeometry::default(),
            materials: BrakeMaterials::default(),
        }
    }
}

impl BrakeSpec {
    pub fn has(&self, c: Component) -> bool {
        self.components.contains(&c)
    }

    pub fn validate(&self) -> Result<(), InvalidSetting> {
        if self.components.is_empty() {
            return Err(InvalidSetting::new("model.components", " is empty: list at least one of disc, inner_pad, outer_pad, piston, caliper, anchor"));
        }
        if !matches!(
            self.element,
            ElementKind::Hex8 | ElementKind::Hex8I | ElementKind::Hex20 | ElementKind::Hex20R
        ) {
            return Err(InvalidSetting::new(
                "model.element",
                format!(
                    " = '{}': the brake generator makes hexahedra: hex8i, hex8, hex20 or hex20r",
                    self.element.name()
                ),
            ));
        }
        if !(1_000..=50_000_000).contains(&self.target_dofs) {
            return Err(InvalidSetting::new(
                "model.target_dofs",
                format!(
                    " = {}: must be between 1000 and 50,000,000",
                    self.target_dofs
                ),
            ));
        }
        if !(self.pressure_bar.is_finite() && self.pressure_bar >= 0.0) {
            return Err(InvalidSetting::new(
                "model.pressure_bar",
                format!(
                    " = {}: must be a finite pressure >= 0 (bar)",
                    self.pressure_bar
                ),
            ));
        }
        self.geometry.validate()?;
        for (key, m) in [
            ("disc", &self.materials.disc),
            ("lining", &self.materials.lining),
            ("backplate", &self.materials.backplate),
            ("piston", &self.materials.piston),
            ("caliper", &self.materials.caliper),
            ("anchor", &self.materials.anchor),
        ] {
            m.validate().map_err(|e| {
                InvalidSetting::new(format!("model.materials.{key}"), format!(": {e}"))
            })?;
        }
        Ok(())
    }
}

/// A generated brake: mesh, constraints, interfaces and loads.
#[derive(Debug, Clone)]
pub struct BrakeModel {
    pub mesh: Mesh,
    pub clamps: Vec<Clamp>,
    pub interfaces: Vec<Interface>,
    pub loads: Vec<PressureLoad>,
    /// Pa.
    pub pressure: f64,
    /// The element size the sizing chose (m).
    pub element_size: f64,
    /// What the absence of a component changed, for the log.
    pub notes: Vec<String>,
}

type GridOf = fn(&BrakeGeometry, f64) -> (Grid, Selector);

/// A component's grid at element size h.
type GridAt<'a> = Box<dyn Fn(f64) -> (Grid, Selector) + 'a>;

fn grids(spec: &BrakeSpec) -> Vec<GridAt<'_>> {
    let g = &spec.geometry;
    let mut out: Vec<GridAt<'_>> = Vec::new();
    let simple: [(Component, GridOf); 4] = [
        (Component::Disc, disc::grid),
        (Component::Piston, piston::grid),
        (Component::Caliper, caliper::grid),
        (Component::Anchor, anchor::grid),
    ];
    for (c, f) in simple {
        if spec.has(c) {
            out.push(Box::new(move |h| f(g, h)));
        }
    }
    for (c, side) in [
        (Component::InnerPad, Side::Inner),
        (Component::OuterPad, Side::Outer),
    ] {
        if spec.has(c) {
            out.push(Box::new(move |h| pad::grid(g, side, h)));
        }
    }
    out
}

/// Nodes of the brake at element size `h`, without meshing it.
pub fn count_nodes(spec: &BrakeSpec, h: f64) -> usize {
    grids(spec)
        .iter()
        .map(|f| {
            let (grid, select) = f(h);
            grid.count_nodes(spec.element, &*select)
        })
        .sum()
}

/// The element size whose node count x 3 is nearest to `target_dofs` (bisection on log h;
/// the count is a non-increasing step function of h).
pub fn element_size_for(spec: &BrakeSpec) -> Result<f64, InvalidSetting> {
    let target = spec.target_dofs as f64;
    let dofs = |h: f64| 3.0 * count_nodes(spec, h) as f64;
    let mut coarse = 0.05_f64;
    if dofs(coarse) > 1.1 * target {
        return Err(InvalidSetting::new(
            "model.target_dofs",
            format!(
                " = {}: the coarsest mesh of these components has {} DOF; ask for more",
                spec.target_dofs,
                dofs(coarse)
            ),
        ));
    }
    // Halve until the count passes the target (each halving multiplies it by up to 8).
    let mut fine = coarse;
    while dofs(fine) < target {
        coarse = fine;
        fine /= 2.0;
    }
    let mut best = (coarse, dofs(coarse));
    for _ in 0..60 {
        let h = (fine * coarse).sqrt();
        let n = dofs(h);
        if (n - target).abs() < (best.1 - target).abs() {
            best = (h, n);
        }
        if n > target {
            fine = h;
        } else {
            coarse = h;
        }
        if coarse / fine < 1.0 + 1e-6 {
            break;
        }
    }
    if (best.1 - target).abs() > 0.1 * target {
        return Err(InvalidSetting::new(
            "model.target_dofs",
            format!(
                " = {}: the nearest mesh has {} DOF (more than 10 % off); try a different target",
                spec.target_dofs, best.1
            ),
        ));
    }
    Ok(best.0)
}

/// Generates the brake the spec asks for. Every component is meshed independently and
/// appended; lining and backplate of a pad share nodes. Boundary conditions: the disc is
/// clamped on its hub face around the bolt circle, the anchor at its bolt faces, the caliper
/// slides along z on its pins (x, y held at the pin bosses). A missing neighbour is replaced
/// by its constraint: without the anchor the backplate ears are held in x and y; without the
/// caliper the outer backplate's back is held in z; without the piston the pressure acts on
/// the inner backplate's back.
pub fn generate(spec: &BrakeSpec) -> Result<BrakeModel, InvalidSetting> {
    spec.validate()?;
    let h = element_size_for(spec)?;
    Ok(generate_with_size(spec, h))
}

/// As `generate`, at a given element size.
pub fn generate_with_size(spec: &BrakeSpec, h: f64) -> BrakeModel {
    let g = &spec.geometry;
    let mats = &spec.materials;
    let kind = spec.element;
    let mut mesh = Mesh::default();
    let mut clamps = Vec::new();
    let mut interfaces = Vec::new();
    let mut loads = Vec::new();
    let mut notes = Vec::new();
    let mut add = |part: GridMesh| mesh.append(part.mesh);
    if spec.has(Component::Disc) {
        add(disc::mesh(g, &mats.disc, h, kind));
        clamps.push(Clamp::all("disc_bolts"));
    }
    for (c, side) in [
        (Component::InnerPad, Side::Inner),
        (Component::OuterPad, Side::Outer),
    ] {
        if !spec.has(c) {
            continue;
        }
        let s = side.name();
        add(pad::mesh(g, side, &mats.lining, &mats.backplate, h, kind));
        if spec.has(Component::Disc) {
            interfaces.push(Interface {
                name: format!("{s}_lining_disc"),
                master: format!("{s}_lining_friction"),
                slave: format!("disc_friction_{s}"),
                kind: InterfaceKind::Sliding,
            });
        }
        if spec.has(Component::Anchor) {
            interfaces.push(Interface {
                name: format!("{s}_backplate_abutments"),
                master: format!("{s}_backplate_ears"),
                slave: "anchor_abutments".into(),
                kind: InterfaceKind::Sticking,
            });
        } else {
            clamps.push(Clamp {
                node_set: format!("{s}_backplate_ears"),
                components: [true, true, false],
            });
            notes.push(format!(
                "no anchor: the {s} backplate ears are held in x and y"
            ));
        }
    }
    if spec.has(Component::Piston) {
        add(piston::mesh(g, &mats.piston, h, kind));
        loads.push(PressureLoad {
            surface: "piston_bottom".into(),
            area: piston::hydraulic_area(g),
        });
        if spec.has(Component::InnerPad) {
            interfaces.push(Interface {
                name: "piston_inner_backplate".into(),
                master: "piston_rim".into(),
                slave: "inner_backplate_back".into(),
                kind: InterfaceKind::Sticking,
            });
        }
    } else if spec.has(Component::InnerPad) {
        loads.push(PressureLoad {
            surface: "inner_backplate_back".into(),
            area: piston::hydraulic_area(g),
        });
        notes.push("no piston: the brake pressure acts on the inner backplate's back".into());
    }
    if spec.has(Component::Caliper) {
        add(caliper::mesh(g, &mats.caliper, h, kind));
        clamps.push(Clamp {
            node_set: "caliper_pins".into(),
            components: [true, true, false],
        });
        if spec.has(Component::Piston) {
            loads.push(PressureLoad {
                surface: "caliper_bore".into(),
                area: piston::hydraulic_area(g),
            });
        }
        if spec.has(Component::OuterPad) {
            interfaces.push(Interface {
                name: "fingers_outer_backplate".into(),
                master: "caliper_fingers".into(),
                slave: "outer_backplate_back".into(),
                kind: InterfaceKind::Sticking,
            });
        }
    } else if spec.has(Component::OuterPad) {
        clamps.push(Clamp {
            node_set: "outer_backplate_back".into(),
            components: [false, false, true],
        });
        notes.push("no caliper: the outer backplate's back is held in z".into());
    }
    if spec.has(Component::Anchor) {
        add(anchor::mesh(g, &mats.anchor, h, kind));
        clamps.push(Clamp::all("anchor_bolts"));
    }
    BrakeModel {
        mesh,
        clamps,
        interfaces,
        loads,
        pressure: spec.pressure_bar * 1e5,
        element_size: h,
        notes,
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn default_geometry_is_consistent() {
        BrakeSpec::default().validate().unwrap();
    }

    #[test]
    fn a_piston_wider_than_the_pad_is_rejected_with_the_reason() {
        let mut spec = BrakeSpec::default();
        spec.geometry.piston_diameter = 0.070;
        let e = spec.validate().unwrap_err();
        assert!(e.to_string().contains("caliper does not fit"), "{e}");
    }
}
