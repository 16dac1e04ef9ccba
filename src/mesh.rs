//! gmsh MSH 4.1 reader (ASCII and binary) → plain [`Mesh`].
//!
//! Place in the flow: first stage after the scene; `model` turns a `Mesh` into bodies,
//! boundary loops and interfaces. This module knows nothing about bodies or conditions:
//! it reports what the file holds (physical names, entities with their physical tags and
//! signed bounding curves, nodes, 2-node lines, 3-node triangles) and rejects what it
//! cannot hold, naming the section and line (or byte offset) of the problem.

use std::collections::BTreeMap;
use std::path::Path;

use crate::error::{Error, Result};

/// A `$PhysicalNames` entry.
#[derive(Debug, Clone, PartialEq)]
pub struct PhysicalName {
    pub dim: i32,
    pub tag: i32,
    pub name: String,
}

/// A geometric entity of `$Entities` (point, curve or surface).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Entity {
    pub tag: i32,
    /// Physical group tags this entity belongs to.
    pub physical_tags: Vec<i32>,
    /// Signed tags of the bounding entities of dimension `dim - 1` (empty for points).
    /// For a surface: its bounding curves, the sign giving the orientation gmsh used.
    pub bounding: Vec<i32>,
}

/// A 2-node line element, nodes as indices into [`Mesh::nodes`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    pub tag: usize,
    pub nodes: [usize; 2],
    /// Tag of the curve entity the element lies on.
    pub curve: i32,
}

/// A 3-node triangle, nodes as indices into [`Mesh::nodes`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Triangle {
    pub tag: usize,
    pub nodes: [usize; 3],
    /// Tag of the surface entity the element lies in.
    pub surface: i32,
}

/// What a MSH 4.1 file holds, in file order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh {
    /// True when the file was binary.
    pub binary: bool,
    pub physical_names: Vec<PhysicalName>,
    pub points: BTreeMap<i32, Entity>,
    pub curves: BTreeMap<i32, Entity>,
    pub surfaces: BTreeMap<i32, Entity>,
    /// Node coordinates (x, y); z must be 0 and is dropped.
    pub nodes: Vec<[f64; 2]>,
    /// gmsh node tag of each node (same order as `nodes`).
    pub node_tags: Vec<usize>,
    pub lines: Vec<Line>,
    pub triangles: Vec<Triangle>,
}

impl Mesh {
    /// Physical name of the group (dim, tag), if named.
    pub fn physical_name(&self, dim: i32, tag: i32) -> Option<&str> {
        self.physical_names
            .iter()
            .find(|p| p.dim == dim && p.tag == tag)
            .map(|p| p.name.as_str())
    }
}

/// Reads a MSH 4.1 file (ASCII or binary).
pub fn read_msh(path: &Path) -> Result<Mesh> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, format!("cannot read the mesh: {e}")))?;
    parse_msh(&bytes, path)
}

/// Parses MSH 4.1 content; `source` names the file in messages.
pub fn parse_msh(_bytes: &[u8], source: &Path) -> Result<Mesh> {
    Err(Error::input(source, "MSH reader not implemented yet"))
}
