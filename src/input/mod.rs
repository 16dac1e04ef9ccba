//! Input: the scene file, its expressions, the gmsh mesh and the model built from both.

pub mod expr;
pub mod gmsh;
pub mod mesh;
pub mod model;
pub mod pairing;
pub mod scene;
pub mod tables;
