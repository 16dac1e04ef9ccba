//! sgbem: contact and detachment of 2D elastic bodies by the symmetric Galerkin boundary
//! element method (SGBEM).
//!
//! The modules follow the data flow; each depends only on those listed before it:
//! `error` → `expr` → `scene` → `mesh` → `model` → `kernels` → `quadrature` → `galerkin`
//! → `plan` (the effects a scene calls for) → `report` (what `sgbem check` prints)
//! → `pipeline` (the stage order).

pub mod assembly;
pub mod condensation;
pub mod contact;
pub mod error;
pub mod expr;
pub mod galerkin;
pub mod interface;
pub mod kernels;
pub mod lcp;
pub mod mesh;
pub mod model;
pub mod output;
pub mod pipeline;
pub mod plan;
pub mod postprocess;
pub mod qp;
pub mod quadrature;
pub mod report;
pub mod scene;
pub mod solution;
pub mod solve;
