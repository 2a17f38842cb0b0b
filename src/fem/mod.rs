//! Finite-element core: shape functions, quadrature, materials, element kernels, DOF map and
//! generic assembly. Pure Rust: no MPI, no PETSc.

pub mod assembly;
pub mod dofmap;
pub mod element;
pub mod petsc;
pub mod quadrature;
pub mod quality;
pub mod shape;
