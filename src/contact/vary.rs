//! A contact-law parameter of the sliding interfaces changed to a value: what the sweeps,
//! the noise matrix and the parameter shapes vary.

use super::law::{FrictionLaw, NormalLaw};
use super::ResolvedInterface;

/// A parameter of the sliding interfaces' laws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LawParameter {
    /// The friction coefficient (coulomb and arctan laws).
    Mu,
    /// p0 and lambda of the exponential normal law.
    P0,
    Lambda,
}

impl LawParameter {
    pub fn name(self) -> &'static str {
        match self {
            LawParameter::Mu => "mu",
            LawParameter::P0 => "p0",
            LawParameter::Lambda => "lambda",
        }
    }
}

/// A swept parameter that an interface's law does not have.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{parameter} varied: interface '{interface}' has the law {law}; {needs}")]
pub struct LawMismatch {
    pub interface: String,
    pub parameter: &'static str,
    pub law: String,
    pub needs: &'static str,
}

/// Sets a law parameter on the sliding interfaces. Errors name an interface whose law has no
/// such parameter.
pub fn set_law_parameter(
    parameter: LawParameter,
    value: f64,
    interfaces: &mut [ResolvedInterface],
) -> Result<(), LawMismatch> {
    for i in interfaces.iter_mut().filter(|i| i.friction.is_sliding()) {
        match parameter {
            LawParameter::Mu => {
                i.friction = match i.friction {
                    FrictionLaw::Coulomb { slip_speed, .. } => FrictionLaw::Coulomb {
                        mu: value,
                        slip_speed,
                    },
                    FrictionLaw::Arctan { slip_speed, .. } => FrictionLaw::Arctan {
                        mu: value,
                        slip_speed,
                    },
                    other => {
                        return Err(LawMismatch {
                            interface: i.name.clone(),
                            parameter: parameter.name(),
                            law: format!("{other:?}"),
                            needs: "varying mu needs the coulomb or arctan friction law",
                        })
                    }
                }
            }
            LawParameter::P0 | LawParameter::Lambda => {
                let NormalLaw::Exponential {
                    p0,
                    lambda,
                    linear_below_gap,
                } = i.normal
                else {
                    return Err(LawMismatch {
                        interface: i.name.clone(),
                        parameter: parameter.name(),
                        law: format!("{:?}", i.normal),
                        needs: "varying p0 or lambda needs the exponential law",
                    });
                };
                i.normal = if parameter == LawParameter::P0 {
                    NormalLaw::Exponential {
                        p0: value,
                        lambda,
                        linear_below_gap,
                    }
                } else {
                    NormalLaw::Exponential {
                        p0,
                        lambda: value,
                        linear_below_gap,
                    }
                };
            }
        }
    }
    Ok(())
}
