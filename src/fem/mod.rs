//! Finite-element core: shape functions, quadrature, materials, element kernels, DOF map and
//! generic assembly. Pure Rust: no MPI, no PETSc.

pub mod assembly;
pub mod dense;
pub mod dofmap;
pub mod element;
pub mod material;
pub mod quadrature;
pub mod shape;
