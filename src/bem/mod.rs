//! The boundary element stage: kernels, quadrature, Galerkin element-pair integrals,
//! per-body assembly and condensation onto the interface unknowns.

pub mod assembly;
pub(crate) mod condensation;
pub mod galerkin;
pub mod kernels;
pub mod operators;
pub mod quadrature;

pub use operators::{prepare, Operators};
