//! The `[contact]` table of a scene (serde schema, defaults, validation) and the laws it
//! resolves per interface.

use crate::invalid::InvalidSetting;
use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::law::{FrictionLaw, NormalLaw};
use super::pairing::Axis;
use super::surface;
use crate::mesh::{Interface, InterfaceKind};

/// The `[contact]` table of a scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSettings {
    /// Disc speed Omega (rad/s) about `axis`; positive turns e_theta = axis x e_r.
    #[serde(default = "default_disc_speed")]
    pub disc_speed: f64,
    #[serde(default = "default_axis")]
    pub axis: [f64; 3],
    #[serde(default)]
    pub center: [f64; 3],
    /// Gauss points per direction on the master faces (quadrilaterals n x n; triangles 1,
    /// 3 or 6 points).
    #[serde(default = "default_gauss")]
    pub gauss_points: usize,
    /// Largest distance (m) between a master point and its projection; farther points miss.
    #[serde(default = "default_search")]
    pub search_distance: f64,
    /// Laws of the sliding interfaces (pad linings on the disc).
    #[serde(default = "default_sliding")]
    pub sliding: InterfaceLaws,
    /// Laws of the sticking interfaces (component joints).
    #[serde(default = "default_sticking")]
    pub sticking: InterfaceLaws,
    /// Per-interface overrides, by interface name.
    #[serde(default)]
    pub interfaces: BTreeMap<String, InterfaceLaws>,
}

fn default_disc_speed() -> f64 {
    2.0 * std::f64::consts::PI
}
fn default_axis() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}
fn default_gauss() -> usize {
    2
}
fn default_search() -> f64 {
    1e-3
}
fn default_sliding() -> InterfaceLaws {
    InterfaceLaws {
        normal: NormalLaw::Exponential {
            p0: 1e6,
            lambda: 2e5,
            linear_below_gap: None,
        },
        friction: FrictionLaw::Coulomb {
            mu: 0.4,
            slip_speed: 1e-3,
        },
    }
}
fn default_sticking() -> InterfaceLaws {
    InterfaceLaws {
        normal: NormalLaw::Exponential {
            p0: 1e6,
            lambda: 2e5,
            linear_below_gap: None,
        },
        friction: FrictionLaw::Stick { mu: 0.2 },
    }
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings {
            disc_speed: default_disc_speed(),
            axis: default_axis(),
            center: [0.0; 3],
            gauss_points: default_gauss(),
            search_distance: default_search(),
            sliding: default_sliding(),
            sticking: default_sticking(),
            interfaces: BTreeMap::new(),
        }
    }
}

/// Normal and tangential law of an interface.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InterfaceLaws {
    pub normal: NormalLaw,
    pub friction: FrictionLaw,
}

impl ContactSettings {
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        if !self.disc_speed.is_finite() {
            return Err(InvalidSetting::new(
                "contact.disc_speed",
                format!(" = {}: must be finite (rad/s)", self.disc_speed),
            ));
        }
        if surface::norm(self.axis) < 1e-12 || self.axis.iter().any(|a| !a.is_finite()) {
            return Err(InvalidSetting::new(
                "contact.axis",
                format!(" = {:?}: must be a non-zero vector", self.axis),
            ));
        }
        if !(1..=4).contains(&self.gauss_points) {
            return Err(InvalidSetting::new(
                "contact.gauss_points",
                format!(" = {}: must be 1 to 4", self.gauss_points),
            ));
        }
        if !(self.search_distance.is_finite() && self.search_distance > 0.0) {
            return Err(InvalidSetting::new(
                "contact.search_distance",
                format!(" = {}: must be a positive length (m)", self.search_distance),
            ));
        }
        let mut all: Vec<(String, &InterfaceLaws)> = vec![
            ("contact.sliding".into(), &self.sliding),
            ("contact.sticking".into(), &self.sticking),
        ];
        all.extend(
            self.interfaces
                .iter()
                .map(|(k, v)| (format!("contact.interfaces.{k}"), v)),
        );
        for (key, laws) in all {
            let normal = format!("{key}.normal");
            laws.normal.validate().map_err(|e| e.within(&normal))?;
            let friction = format!("{key}.friction");
            laws.friction.validate().map_err(|e| e.within(&friction))?;
        }
        Ok(())
    }

    /// Each interface of the model with its laws; an override naming no interface is an error.
    pub fn resolve(
        &self,
        interfaces: &[Interface],
    ) -> Result<Vec<ResolvedInterface>, InvalidSetting> {
        for name in self.interfaces.keys() {
            if !interfaces.iter().any(|i| &i.name == name) {
                let names: Vec<&str> = interfaces.iter().map(|i| i.name.as_str()).collect();
                let detail = format!(
                    ": the model has no interface '{name}' (it has: {})",
                    names.join(", ")
                );
                return Err(InvalidSetting::new(
                    format!("contact.interfaces.{name}"),
                    detail,
                ));
            }
        }
        Ok(interfaces
            .iter()
            .map(|i| {
                let laws = self
                    .interfaces
                    .get(&i.name)
                    .copied()
                    .unwrap_or(match i.kind {
                        InterfaceKind::Sliding => self.sliding,
                        InterfaceKind::Sticking => self.sticking,
                    });
                ResolvedInterface {
                    name: i.name.clone(),
                    master: i.master.clone(),
                    slave: i.slave.clone(),
                    normal: laws.normal,
                    friction: laws.friction,
                }
            })
            .collect())
    }

    pub fn axis(&self) -> Axis {
        Axis {
            direction: surface::normalize(self.axis),
            center: self.center,
        }
    }
}

/// An interface with its laws.
#[derive(Debug, Clone, PartialEq)]
pub struct ResolvedInterface {
    pub name: String,
    pub master: String,
    pub slave: String,
    pub normal: NormalLaw,
    pub friction: FrictionLaw,
}
