//! sgbem: contact and detachment of 2D elastic bodies by the symmetric Galerkin boundary
//! element method (SGBEM).
//!
//! One folder per stage, in data-flow order; each depends only on the stages before it:
//!
//! * `error` — one error enum whose messages name the file, key or group and the fix;
//! * `input` — scene (TOML), expressions, the MSH 4.1 reader, the model (bodies, loops,
//!   parts, interface pairs, unknowns);
//! * `bem` — kernels, quadrature, Galerkin pair integrals, per-body assembly, condensation;
//!   its output, every body's operators (`bem::Operators`, `bem::prepare`), is the contact
//!   stage's input;
//! * `solution` — plain result records;
//! * `contact` — the interface problem, its solvers (peers over one inner problem) and the
//!   driver of load steps and collapse searches (`contact::driver`);
//! * `post` — boundary stresses, interior fields, sections;
//! * `output` — summary, archive, VTK, CSV (they read result records; nothing imports them);
//! * `estimate` (memory and time of a run, before assembling it); `linalg`, `vec2` and
//!   `timings`, small shared utilities;
//! * `plan` (the effects a scene calls for), `report` (what `sgbem check` prints) and
//!   `pipeline` (the only module that knows the stage order).

pub mod bem;
pub mod contact;
pub mod error;
pub mod estimate;
pub mod input;
pub(crate) mod linalg;
pub mod output;
pub mod pipeline;
pub mod plan;
pub mod post;
pub mod report;
pub mod solution;
pub mod sweep;
pub mod timings;
pub(crate) mod vec2;
