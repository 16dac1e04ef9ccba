//! gmsh MSH 4.1 reader (ASCII and binary) → plain [`Mesh`].
//!
//! Place in the flow: first stage after the scene; `model` turns a `Mesh` into bodies,
//! boundary loops and interfaces. This module knows nothing about bodies or conditions:
//! it reports what the file holds (physical names, entities with their physical tags and
//! signed bounding curves, nodes, 2-node lines, 3-node triangles) and rejects what it
//! cannot hold, naming the section and line (or byte offset) of the problem.
//!
//! What it reads: `$MeshFormat` (version 4.1 only, ASCII or binary, 8-byte reals),
//! `$PhysicalNames`, `$Entities` (points, curves, surfaces; volumes are refused),
//! `$Nodes` and `$Elements` (entity blocks; parametric node coordinates are skipped).
//! Element types: 2-node lines (1) on curves, 3-node triangles (2) in surfaces, points (15,
//! ignored); any other type is refused with the gmsh option that avoids it. Sections it does
//! not use (`$Periodic`, `$NodeData`, `$Comments`, …) are skipped up to their `$End…`
//! marker; `$PartitionedEntities` is refused. Node z coordinates must be 0.
//!
//! In a binary file, every number of `$Entities`, `$Nodes` and `$Elements` is little-endian
//! binary: counts and node/element tags are `size_t` (u64), entity tags, dimensions, element
//! types and flags are `int` (i32), coordinates `double`; `$MeshFormat` and `$PhysicalNames`
//! stay text, and `$MeshFormat` carries the int 1 that tells the byte order.
//!
//! Why a reader of our own rather than the `mshio` crate: mshio is unmaintained and pulls in
//! a dependency with a RustSec advisory. The part of the format sgbem needs is small, and a
//! reader written for it validates as it reads (counts against the bytes left, node tags of
//! elements, z = 0, element types) and names the section and the line (ASCII) or byte
//! offset (binary) in every error. It never panics on any input: counts read from the file
//! are checked against the remaining input before anything is allocated for them.

use std::collections::{BTreeMap, HashMap, HashSet};
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
    let bytes =
        std::fs::read(path).map_err(|e| Error::io(path, format!("cannot read the mesh: {e}")))?;
    parse_msh(&bytes, path)
}

/// Parses MSH 4.1 content; `source` names the file in messages.
pub fn parse_msh(bytes: &[u8], source: &Path) -> Result<Mesh> {
    Parser {
        cur: Cursor {
            bytes,
            pos: 0,
            source,
            binary: false,
            section: "",
        },
        mesh: Mesh::default(),
        node_index: HashMap::new(),
        node_z: Vec::new(),
    }
    .run()
}

/// The advice every refused format version gets.
const RESAVE: &str = "re-save it with `gmsh -format msh41` (e.g. `gmsh -2 -format msh41 body.geo`)";

/// Bytes of one item in a binary section, for the count guards.
const I32: usize = 4;
const U64: usize = 8;
const F64: usize = 8;

/// Position-aware reader over the raw bytes. Text numbers are whitespace-separated tokens;
/// binary numbers are little-endian fixed-size fields.
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    source: &'a Path,
    /// Whether the file is binary: decides how numbers of the data sections are read and
    /// whether errors give a line (text) or a byte offset (binary).
    binary: bool,
    /// Section being read, for messages ("" between sections).
    section: &'static str,
}

impl<'a> Cursor<'a> {
    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    fn at_eof(&self) -> bool {
        self.pos >= self.bytes.len()
    }

    /// "line 12" for text files, "byte 1234" for binary ones.
    fn location(&self, at: usize) -> String {
        if self.binary {
            format!("byte {at}")
        } else {
            let before = self.bytes.get(..at).unwrap_or(self.bytes);
            let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
            format!("line {line}")
        }
    }

    /// An input error located at byte `at` of the current section.
    fn error_at(&self, at: usize, message: impl AsRef<str>) -> Error {
        let location = self.location(at);
        let message = message.as_ref();
        if self.section.is_empty() {
            Error::input(self.source, format!("{location}: {message}"))
        } else {
            Error::input(
                self.source,
                format!("in {} at {location}: {message}", self.section),
            )
        }
    }

    /// An input error about the section as a whole (no precise position).
    fn error(&self, message: impl AsRef<str>) -> Error {
        Error::input(
            self.source,
            format!("in {}: {}", self.section, message.as_ref()),
        )
    }

    fn eof_error(&self, what: &str) -> Error {
        self.error_at(self.pos, format!("unexpected end of file: expected {what}"))
    }

    /// Where the next number starts, for messages: past the whitespace in text (a no-op
    /// on binary data, where whitespace bytes are data).
    fn here(&mut self) -> usize {
        if !self.binary {
            self.skip_whitespace();
        }
        self.pos
    }

    /// Where the next text token starts, also in the text parts of binary files.
    fn text_here(&mut self) -> usize {
        self.skip_whitespace();
        self.pos
    }

    fn skip_whitespace(&mut self) {
        while self
            .bytes
            .get(self.pos)
            .is_some_and(|b| b.is_ascii_whitespace())
        {
            self.pos += 1;
        }
    }

    /// Next whitespace-separated token and its start offset.
    fn token(&mut self, what: &str) -> Result<(usize, &'a [u8])> {
        self.skip_whitespace();
        let start = self.pos;
        while self
            .bytes
            .get(self.pos)
            .is_some_and(|b| !b.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        match self.bytes.get(start..self.pos) {
            Some(token) if !token.is_empty() => Ok((start, token)),
            _ => Err(self.eof_error(what)),
        }
    }

    /// Next token parsed as text number `T`.
    fn text<T: std::str::FromStr>(&mut self, what: &str) -> Result<T> {
        let (start, token) = self.token(what)?;
        std::str::from_utf8(token)
            .ok()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| {
                self.error_at(start, format!("expected {what}, found '{}'", shown(token)))
            })
    }

    fn text_size(&mut self, what: &str) -> Result<usize> {
        let (start, token) = self.token(what)?;
        std::str::from_utf8(token)
            .ok()
            .and_then(|s| s.parse::<u64>().ok())
            .and_then(|v| usize::try_from(v).ok())
            .ok_or_else(|| {
                self.error_at(
                    start,
                    format!(
                        "expected {what} (a non-negative integer), found '{}'",
                        shown(token)
                    ),
                )
            })
    }

    fn take<const N: usize>(&mut self, what: &str) -> Result<[u8; N]> {
        let end = self
            .pos
            .checked_add(N)
            .ok_or_else(|| self.eof_error(what))?;
        let field = self
            .bytes
            .get(self.pos..end)
            .and_then(|s| <[u8; N]>::try_from(s).ok())
            .ok_or_else(|| self.eof_error(what))?;
        self.pos = end;
        Ok(field)
    }

    /// An `int` of a data section.
    fn int(&mut self, what: &str) -> Result<i32> {
        if self.binary {
            self.take::<I32>(what).map(i32::from_le_bytes)
        } else {
            self.text(what)
        }
    }

    /// A `size_t` (count or node/element tag) of a data section.
    fn size(&mut self, what: &str) -> Result<usize> {
        if self.binary {
            let start = self.pos;
            let value = u64::from_le_bytes(self.take::<U64>(what)?);
            usize::try_from(value)
                .map_err(|_| self.error_at(start, format!("{what} {value} is too large")))
        } else {
            self.text_size(what)
        }
    }

    /// A `double` of a data section.
    fn real(&mut self, what: &str) -> Result<f64> {
        if self.binary {
            self.take::<F64>(what).map(f64::from_le_bytes)
        } else {
            self.text(what)
        }
    }

    /// Refuses a count of items that cannot fit in what is left of the file: `bytes` per
    /// item when binary, `numbers` text numbers per item (each at least a digit and a
    /// separator) when text. Guards every allocation and loop sized by the file.
    fn check_count(
        &self,
        at: usize,
        count: usize,
        bytes: usize,
        numbers: usize,
        what: &str,
    ) -> Result<()> {
        let per_item = if self.binary {
            bytes
        } else {
            numbers.saturating_mul(2)
        };
        self.check_fits(at, count, per_item, what)
    }

    /// Refuses `count` items of at least `per_item` bytes each beyond the end of the file.
    fn check_fits(&self, at: usize, count: usize, per_item: usize, what: &str) -> Result<()> {
        let fits = count
            .checked_mul(per_item)
            .is_some_and(|need| need <= self.remaining().saturating_add(1));
        if fits {
            Ok(())
        } else {
            Err(self.error_at(
                at,
                format!(
                    "{count} {what} declared, more than the {} bytes left in the file can hold \
                     (truncated or corrupt file?)",
                    self.remaining()
                ),
            ))
        }
    }

    /// After a section header in a binary file: the rest of the header line, up to and
    /// including its newline, so that the binary data starts exactly after it.
    fn end_of_line(&mut self, what: &str) -> Result<()> {
        while let Some(&b) = self.bytes.get(self.pos) {
            self.pos += 1;
            match b {
                b'\n' => return Ok(()),
                b' ' | b'\t' | b'\r' => {}
                _ => {
                    return Err(self.error_at(
                        self.pos - 1,
                        format!("expected the end of the line before {what}"),
                    ))
                }
            }
        }
        Err(self.eof_error(what))
    }

    /// The `$End…` marker closing the current section.
    fn expect_end(&mut self, marker: &str) -> Result<()> {
        let (start, token) = self.token(marker)?;
        if token == marker.as_bytes() {
            Ok(())
        } else {
            Err(self.error_at(
                start,
                format!(
                    "expected {marker}, found '{}' (the counts of the section do not match \
                     its content)",
                    shown(token)
                ),
            ))
        }
    }
}

/// A file token for a message: lossy UTF-8, at most 40 characters.
fn shown(token: &[u8]) -> String {
    let text = String::from_utf8_lossy(token);
    let mut short: String = text.chars().take(40).collect();
    if text.chars().nth(40).is_some() {
        short.push('…');
    }
    short
}

struct Parser<'a> {
    cur: Cursor<'a>,
    mesh: Mesh,
    /// gmsh node tag → index into `mesh.nodes`.
    node_index: HashMap<usize, usize>,
    /// z of each node, checked once the coordinate scale is known.
    node_z: Vec<f64>,
}

impl Parser<'_> {
    fn run(mut self) -> Result<Mesh> {
        let mut seen: HashSet<&'static str> = HashSet::new();
        loop {
            self.cur.section = "";
            self.cur.skip_whitespace();
            if self.cur.at_eof() {
                break;
            }
            let (start, token) = self.cur.token("a section header")?;
            if seen.is_empty() && token != b"$MeshFormat" {
                let hint = if token == b"$NOD" {
                    format!("this is a MSH 1 file; {RESAVE}")
                } else {
                    "is it a gmsh .msh file?".to_string()
                };
                return Err(self.cur.error_at(
                    start,
                    format!(
                        "expected $MeshFormat at the start of the file, found '{}': {hint}",
                        shown(token)
                    ),
                ));
            }
            let section: &'static str = match token {
                b"$MeshFormat" => "$MeshFormat",
                b"$PhysicalNames" => "$PhysicalNames",
                b"$Entities" => "$Entities",
                b"$Nodes" => "$Nodes",
                b"$Elements" => "$Elements",
                b"$PartitionedEntities" => {
                    return Err(self.cur.error_at(
                        start,
                        "$PartitionedEntities: the mesh is partitioned; sgbem needs a whole \
                         mesh (mesh without -part and without Mesh.NbPartitions)",
                    ))
                }
                _ if !token.starts_with(b"$") || token.starts_with(b"$End") => {
                    return Err(self.cur.error_at(
                        start,
                        format!(
                            "expected a section header such as $Nodes, found '{}'",
                            shown(token)
                        ),
                    ))
                }
                _ => {
                    self.skip_section(token)?;
                    continue;
                }
            };
            if !seen.insert(section) {
                return Err(self
                    .cur
                    .error_at(start, format!("a second {section} section")));
            }
            self.cur.section = section;
            match section {
                "$MeshFormat" => self.mesh_format()?,
                "$PhysicalNames" => self.physical_names()?,
                "$Entities" => self.entities()?,
                "$Nodes" => self.nodes()?,
                _ => self.elements()?,
            }
        }
        self.cur.section = "";
        if seen.is_empty() {
            return Err(Error::input(
                self.cur.source,
                "the file is empty: expected a gmsh MSH 4.1 mesh (`gmsh -2 -format msh41 body.geo`)",
            ));
        }
        for required in ["$MeshFormat", "$Entities", "$Nodes", "$Elements"] {
            if !seen.contains(required) {
                return Err(self.cur.error_at(
                    self.cur.bytes.len(),
                    format!(
                        "no {required} section (truncated file? mesh the geometry with \
                         `gmsh -2 -format msh41`)"
                    ),
                ));
            }
        }
        self.check_plane()?;
        self.mesh.binary = self.cur.binary;
        Ok(self.mesh)
    }

    /// Skips a section sgbem does not use, `$Name` … `$EndName`.
    fn skip_section(&mut self, header: &[u8]) -> Result<()> {
        let name = header.get(1..).unwrap_or_default();
        let mut marker = b"$End".to_vec();
        marker.extend_from_slice(name);
        let rest = self.cur.bytes.get(self.cur.pos..).unwrap_or_default();
        match rest.windows(marker.len()).position(|w| w == marker) {
            Some(offset) => {
                self.cur.pos += offset + marker.len();
                Ok(())
            }
            None => Err(self.cur.error_at(
                self.cur.bytes.len(),
                format!(
                    "section {} has no closing {} (truncated file?)",
                    shown(header),
                    shown(&marker)
                ),
            )),
        }
    }

    fn mesh_format(&mut self) -> Result<()> {
        let (start, version) = self.cur.token("the format version (4.1)")?;
        if version != b"4.1" {
            let number = std::str::from_utf8(version)
                .ok()
                .and_then(|s| s.parse::<f64>().ok());
            let message = match number {
                Some(4.1) => None,
                Some(_) => Some(format!(
                    "MSH version {} is not supported: sgbem reads MSH 4.1; {RESAVE}",
                    shown(version)
                )),
                None => Some(format!(
                    "expected the format version 4.1, found '{}'",
                    shown(version)
                )),
            };
            if let Some(message) = message {
                return Err(self.cur.error_at(start, message));
            }
        }
        let at = self.cur.here();
        let file_type: i64 = self.cur.text("the file type (0 ASCII, 1 binary)")?;
        self.cur.binary = match file_type {
            0 => false,
            1 => true,
            other => {
                return Err(self.cur.error_at(
                    at,
                    format!("file type {other} is neither 0 (ASCII) nor 1 (binary); {RESAVE}"),
                ))
            }
        };
        let at = self.cur.text_here();
        let data_size: i64 = self.cur.text("the data size (8)")?;
        if data_size != 8 {
            return Err(self.cur.error_at(
                at,
                format!(
                    "data size {data_size} is not supported: sgbem reads 8-byte reals; {RESAVE}"
                ),
            ));
        }
        if self.cur.binary {
            self.cur.end_of_line("the endianness check")?;
            let at = self.cur.here();
            let one = self.cur.int("the endianness check (int 1)")?;
            if one != 1 {
                return Err(self.cur.error_at(
                    at,
                    format!(
                        "the endianness check reads {one} instead of 1: the file was written \
                         on a big-endian machine; {RESAVE} as ASCII (without -bin) or on this \
                         machine"
                    ),
                ));
            }
        }
        self.cur.expect_end("$EndMeshFormat")
    }

    /// Always text, even in binary files.
    fn physical_names(&mut self) -> Result<()> {
        let at = self.cur.text_here();
        let count = self.cur.text_size("the number of physical names")?;
        // Each entry is at least `d t ""` and a newline.
        self.cur.check_fits(at, count, 7, "physical names")?;
        for _ in 0..count {
            let dim = self.cur.text("the dimension of a physical name")?;
            let tag = self.cur.text("the tag of a physical name")?;
            let name = self.quoted_name()?;
            self.mesh
                .physical_names
                .push(PhysicalName { dim, tag, name });
        }
        self.cur.expect_end("$EndPhysicalNames")
    }

    /// `"name"` (may hold spaces, not quotes).
    fn quoted_name(&mut self) -> Result<String> {
        self.cur.skip_whitespace();
        let start = self.cur.pos;
        if self.cur.bytes.get(start) != Some(&b'"') {
            return match self.cur.bytes.get(start) {
                None => Err(self.cur.eof_error("a quoted physical name")),
                Some(_) => Err(self
                    .cur
                    .error_at(start, "expected a quoted physical name (\"name\")")),
            };
        }
        let rest = self.cur.bytes.get(start + 1..).unwrap_or_default();
        let Some(len) = rest.iter().position(|&b| b == b'"' || b == b'\n') else {
            return Err(self
                .cur
                .error_at(start, "physical name without closing quote"));
        };
        let raw = rest.get(..len).unwrap_or_default();
        if rest.get(len) != Some(&b'"') {
            return Err(self
                .cur
                .error_at(start, "physical name without closing quote on its line"));
        }
        let name = std::str::from_utf8(raw)
            .map_err(|_| self.cur.error_at(start, "physical name is not valid UTF-8"))?;
        self.cur.pos = start + len + 2;
        Ok(name.to_string())
    }

    fn entities(&mut self) -> Result<()> {
        if self.cur.binary {
            self.cur.end_of_line("the entity counts")?;
        }
        let at = self.cur.here();
        let points = self.cur.size("the number of points")?;
        let curves = self.cur.size("the number of curves")?;
        let surfaces = self.cur.size("the number of surfaces")?;
        let volumes = self.cur.size("the number of volumes")?;
        if volumes > 0 {
            return Err(self.cur.error_at(
                at,
                format!(
                    "3D mesh: sgbem is 2D, and the file has {volumes} volume(s); draw the \
                     bodies as surfaces in the z = 0 plane and mesh with -2"
                ),
            ));
        }
        // Smallest entity records: point `tag x y z nPhys`, curve or surface
        // `tag box(6) nPhys nBound`.
        self.cur
            .check_count(at, points, I32 + 3 * F64 + U64, 5, "points")?;
        self.cur
            .check_count(at, curves, I32 + 6 * F64 + 2 * U64, 9, "curves")?;
        self.cur
            .check_count(at, surfaces, I32 + 6 * F64 + 2 * U64, 9, "surfaces")?;
        for _ in 0..points {
            let at = self.cur.here();
            let tag = self.cur.int("a point tag")?;
            for what in ["the x of a point", "the y of a point", "the z of a point"] {
                self.cur.real(what)?;
            }
            let physical_tags = self.tag_list("physical tags of a point")?;
            let entity = Entity {
                tag,
                physical_tags,
                bounding: Vec::new(),
            };
            if self.mesh.points.insert(tag, entity).is_some() {
                return Err(self.cur.error_at(at, format!("duplicate point tag {tag}")));
            }
        }
        for dim in [1, 2] {
            let (count, kind) = if dim == 1 {
                (curves, "curve")
            } else {
                (surfaces, "surface")
            };
            for _ in 0..count {
                let at = self.cur.here();
                let tag = self.cur.int("an entity tag")?;
                for _ in 0..6 {
                    self.cur.real("a bounding-box coordinate")?;
                }
                let physical_tags = self.tag_list("physical tags")?;
                let bounding = self.tag_list("bounding entity tags")?;
                let entity = Entity {
                    tag,
                    physical_tags,
                    bounding,
                };
                let map = if dim == 1 {
                    &mut self.mesh.curves
                } else {
                    &mut self.mesh.surfaces
                };
                if map.insert(tag, entity).is_some() {
                    return Err(self.cur.error_at(at, format!("duplicate {kind} tag {tag}")));
                }
            }
        }
        self.cur.expect_end("$EndEntities")
    }

    /// A count (size_t) followed by that many ints.
    fn tag_list(&mut self, what: &str) -> Result<Vec<i32>> {
        let at = self.cur.here();
        let count = self.cur.size(&format!("the number of {what}"))?;
        self.cur.check_count(at, count, I32, 1, what)?;
        let mut tags = Vec::with_capacity(count);
        for _ in 0..count {
            tags.push(self.cur.int(what)?);
        }
        Ok(tags)
    }

    fn nodes(&mut self) -> Result<()> {
        if self.cur.binary {
            self.cur.end_of_line("the node counts")?;
        }
        let at = self.cur.here();
        let blocks = self.cur.size("the number of node blocks")?;
        let total = self.cur.size("the number of nodes")?;
        self.cur.size("the smallest node tag")?;
        self.cur.size("the largest node tag")?;
        self.cur
            .check_count(at, blocks, 3 * I32 + U64, 4, "node blocks")?;
        self.cur.check_count(at, total, U64 + 3 * F64, 4, "nodes")?;
        self.mesh.nodes.reserve(total);
        self.mesh.node_tags.reserve(total);
        self.node_z.reserve(total);
        self.node_index.reserve(total);
        let mut read = 0usize;
        for _ in 0..blocks {
            let at = self.cur.here();
            let dim = self.cur.int("the entity dimension of a node block")?;
            let tag = self.cur.int("the entity tag of a node block")?;
            let parametric = self
                .cur
                .int("the parametric flag of a node block (0 or 1)")?;
            let count = self.cur.size("the number of nodes in the block")?;
            if dim == 3 {
                return Err(self.cur.error_at(
                    at,
                    format!("3D mesh: nodes in volume {tag}; sgbem is 2D, mesh with -2"),
                ));
            }
            if !(0..=2).contains(&dim) {
                return Err(self
                    .cur
                    .error_at(at, format!("entity dimension {dim} is not 0, 1 or 2")));
            }
            let extra = match parametric {
                0 => 0,
                1 => dim as usize, // u on curves, u v on surfaces
                _ => {
                    return Err(self.cur.error_at(
                        at,
                        format!("parametric flag {parametric} is neither 0 nor 1"),
                    ))
                }
            };
            self.cur.check_count(
                at,
                count,
                U64 + (3 + extra) * F64,
                4 + extra,
                "nodes in the block",
            )?;
            read = read
                .checked_add(count)
                .filter(|&n| n <= total)
                .ok_or_else(|| {
                    self.cur.error_at(
                        at,
                        format!("the node blocks hold more than the {total} nodes declared"),
                    )
                })?;
            let first = self.mesh.node_tags.len();
            for _ in 0..count {
                let at = self.cur.here();
                let node = self.cur.size("a node tag")?;
                if node == 0 {
                    return Err(self.cur.error_at(at, "node tag 0 (tags start at 1)"));
                }
                let index = self.mesh.node_tags.len();
                if self.node_index.insert(node, index).is_some() {
                    return Err(self.cur.error_at(at, format!("duplicate node tag {node}")));
                }
                self.mesh.node_tags.push(node);
            }
            for i in 0..count {
                let node = self.mesh.node_tags.get(first + i).copied().unwrap_or(0);
                let at = self.cur.here();
                let x = self.cur.real("the x coordinate of a node")?;
                let y = self.cur.real("the y coordinate of a node")?;
                let z = self.cur.real("the z coordinate of a node")?;
                for _ in 0..extra {
                    self.cur.real("a parametric coordinate of a node")?;
                }
                if !(x.is_finite() && y.is_finite() && z.is_finite()) {
                    return Err(self.cur.error_at(
                        at,
                        format!("node {node} has a non-finite coordinate ({x}, {y}, {z})"),
                    ));
                }
                self.mesh.nodes.push([x, y]);
                self.node_z.push(z);
            }
        }
        if read != total {
            return Err(self.cur.error(format!(
                "the header declares {total} nodes but the blocks hold {read}"
            )));
        }
        self.cur.expect_end("$EndNodes")
    }

    fn elements(&mut self) -> Result<()> {
        if self.cur.binary {
            self.cur.end_of_line("the element counts")?;
        }
        let at = self.cur.here();
        let blocks = self.cur.size("the number of element blocks")?;
        let total = self.cur.size("the number of elements")?;
        self.cur.size("the smallest element tag")?;
        self.cur.size("the largest element tag")?;
        self.cur
            .check_count(at, blocks, 3 * I32 + U64, 4, "element blocks")?;
        self.cur.check_count(at, total, 2 * U64, 2, "elements")?;
        let mut element_tags: HashSet<usize> = HashSet::new();
        let mut read = 0usize;
        for _ in 0..blocks {
            let at = self.cur.here();
            let dim = self.cur.int("the entity dimension of an element block")?;
            let entity = self.cur.int("the entity tag of an element block")?;
            let kind = self.cur.int("the element type of an element block")?;
            let count = self.cur.size("the number of elements in the block")?;
            let nodes_per_element = match kind {
                1 => {
                    if dim != 1 || !self.mesh.curves.contains_key(&entity) {
                        return Err(self.cur.error_at(
                            at,
                            format!(
                                "2-node lines (type 1) in entity (dim {dim}, tag {entity}), \
                                 which is not a curve of $Entities"
                            ),
                        ));
                    }
                    2
                }
                2 => {
                    if dim != 2 || !self.mesh.surfaces.contains_key(&entity) {
                        return Err(self.cur.error_at(
                            at,
                            format!(
                                "3-node triangles (type 2) in entity (dim {dim}, tag \
                                 {entity}), which is not a surface of $Entities"
                            ),
                        ));
                    }
                    3
                }
                15 => 1,
                other => {
                    return Err(self.cur.error_at(
                        at,
                        format!(
                            "element type {other} ({}) in entity (dim {dim}, tag {entity}): {}",
                            element_name(other),
                            element_fix(other)
                        ),
                    ))
                }
            };
            self.cur.check_count(
                at,
                count,
                (1 + nodes_per_element) * U64,
                1 + nodes_per_element,
                "elements in the block",
            )?;
            read = read
                .checked_add(count)
                .filter(|&n| n <= total)
                .ok_or_else(|| {
                    self.cur.error_at(
                        at,
                        format!("the element blocks hold more than the {total} elements declared"),
                    )
                })?;
            for _ in 0..count {
                let at = self.cur.here();
                let tag = self.cur.size("an element tag")?;
                if !element_tags.insert(tag) {
                    return Err(self
                        .cur
                        .error_at(at, format!("duplicate element tag {tag}")));
                }
                let mut nodes = [0usize; 3];
                for slot in nodes.iter_mut().take(nodes_per_element) {
                    let at = self.cur.here();
                    let node = self.cur.size("a node tag of an element")?;
                    *slot = *self.node_index.get(&node).ok_or_else(|| {
                        self.cur.error_at(
                            at,
                            format!("element {tag} refers to node {node}, which is not in $Nodes"),
                        )
                    })?;
                }
                match kind {
                    1 => self.mesh.lines.push(Line {
                        tag,
                        nodes: [nodes[0], nodes[1]],
                        curve: entity,
                    }),
                    2 => self.mesh.triangles.push(Triangle {
                        tag,
                        nodes,
                        surface: entity,
                    }),
                    _ => {} // points carry nothing sgbem uses
                }
            }
        }
        if read != total {
            return Err(self.cur.error(format!(
                "the header declares {total} elements but the blocks hold {read}"
            )));
        }
        self.cur.expect_end("$EndElements")
    }

    /// Every z must be 0 up to round-off relative to the size of the drawing.
    fn check_plane(&self) -> Result<()> {
        let scale = self
            .mesh
            .nodes
            .iter()
            .flat_map(|p| p.iter())
            .fold(1.0_f64, |m, c| m.max(c.abs()));
        let tolerance = 1e-9 * scale;
        let off_plane = self
            .node_z
            .iter()
            .zip(&self.mesh.node_tags)
            .find(|(z, _)| z.abs() > tolerance);
        match off_plane {
            Some((z, node)) => Err(Error::input(
                self.cur.source,
                format!("in $Nodes: node {node} has z = {z}: sgbem is 2D: draw in the z = 0 plane"),
            )),
            None => Ok(()),
        }
    }
}

/// gmsh's name of an element type, for messages.
fn element_name(kind: i32) -> &'static str {
    match kind {
        3 => "4-node quadrangle",
        4 => "4-node tetrahedron",
        5 => "8-node hexahedron",
        6 => "6-node prism",
        7 => "5-node pyramid",
        8 => "3-node second-order line",
        9 => "6-node second-order triangle",
        10 => "9-node second-order quadrangle",
        16 => "8-node second-order quadrangle",
        20 | 21 => "third-order triangle",
        22..=25 => "high-order triangle",
        26..=28 => "high-order line",
        11..=14 | 17..=19 | 29..=31 | 92 | 93 => "3D element",
        _ => "unknown type",
    }
}

/// What to change in gmsh to avoid an element type sgbem does not read.
fn element_fix(kind: i32) -> &'static str {
    match kind {
        3 => "sgbem needs triangles: remove Recombine (and Mesh.RecombineAll) from the .geo",
        10 | 16 => {
            "sgbem needs first-order triangles: mesh with -order 1 and remove Recombine \
             from the .geo"
        }
        8 | 9 | 20..=28 => "sgbem needs first-order elements: mesh with -order 1",
        4..=7 | 11..=14 | 17..=19 | 29..=31 | 92 | 93 => {
            "3D mesh: sgbem is 2D; mesh a 2D geometry with -2"
        }
        _ => {
            "sgbem reads 2-node lines (type 1), 3-node triangles (type 2) and points \
             (type 15) only"
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cursor(bytes: &[u8], binary: bool) -> Cursor<'_> {
        Cursor {
            bytes,
            pos: 0,
            source: Path::new("t.msh"),
            binary,
            section: "$Nodes",
        }
    }

    #[test]
    fn shown_cuts_long_tokens_on_character_boundaries() {
        let long = "é".repeat(50);
        let short = shown(long.as_bytes());
        assert_eq!(short.chars().count(), 41);
        assert!(short.ends_with('…'));
        assert_eq!(shown(b"abc"), "abc");
        assert_eq!(shown(&[0xff, b'1']), "\u{fffd}1");
    }

    #[test]
    fn locations_are_lines_in_text_and_bytes_in_binary() {
        let text = cursor(b"a\nb\n\nc", false);
        assert_eq!(text.location(0), "line 1");
        assert_eq!(text.location(2), "line 2");
        assert_eq!(text.location(5), "line 4");
        assert_eq!(text.location(999), "line 4");
        assert_eq!(cursor(b"a\nb", true).location(2), "byte 2");
        let message = text.error_at(2, "boom").to_string();
        assert_eq!(message, "t.msh: in $Nodes at line 2: boom");
    }

    #[test]
    fn binary_fields_stop_at_the_end_of_input() {
        let mut c = cursor(&[1, 0, 0, 0, 7, 0, 0], true);
        assert_eq!(c.int("an int").unwrap(), 1);
        let err = c.int("an int").unwrap_err().to_string();
        assert!(
            err.contains("byte 4") && err.contains("end of file"),
            "{err}"
        );
        assert_eq!(c.pos, 4, "a failed read consumes nothing");
        assert!(c.size("a size").is_err());
        assert!(c.real("a real").is_err());
    }

    #[test]
    fn text_numbers_are_checked() {
        let mut c = cursor(b" 12 -3 x 1.5e3 18446744073709551616", false);
        assert_eq!(c.size("a size").unwrap(), 12);
        assert!(c.size("a size").unwrap_err().to_string().contains("'-3'"));
        assert!(c.int("an int").unwrap_err().to_string().contains("'x'"));
        assert_eq!(c.real("a real").unwrap(), 1500.0);
        assert!(c.size("a size").is_err(), "beyond u64");
        assert!(c
            .token("more")
            .unwrap_err()
            .to_string()
            .contains("end of file"));
    }

    #[test]
    fn count_guards_refuse_what_cannot_fit_without_overflow() {
        let c = cursor(&[0; 64], true);
        assert!(c.check_count(0, 8, 8, 1, "things").is_ok());
        assert!(c.check_count(0, 9, 8, 1, "things").is_err());
        assert!(c.check_count(0, usize::MAX, 8, 1, "things").is_err());
        let t = cursor(b"1 2 3", false);
        assert!(t.check_count(0, 3, 0, 1, "numbers").is_ok());
        assert!(t.check_count(0, 4, 0, 1, "numbers").is_err());
        assert!(t
            .check_count(0, usize::MAX, 0, usize::MAX, "numbers")
            .is_err());
    }

    #[test]
    fn end_of_line_before_binary_data() {
        let mut c = cursor(b" \r\n\x0a", true);
        c.end_of_line("data").unwrap();
        assert_eq!(c.pos, 3, "the 0x0a after the newline is data");
        let mut c = cursor(b" x\n", true);
        assert!(c.end_of_line("data").is_err());
        let mut c = cursor(b"  ", true);
        assert!(c.end_of_line("data").is_err());
    }
}
