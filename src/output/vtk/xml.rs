//! The XML writer of the VTK files: an unstructured grid (`.vtu`) with inline base64 binary
//! arrays, zlib-compressed where the style says so.

use std::fmt::Write as _;

use crate::input::scene::VtkStyle;

/// The values of an array, by their VTK type.
pub(super) enum Values {
    F64(Vec<f64>),
    I32(Vec<i32>),
    U64(Vec<u64>),
    U8(Vec<u8>),
}

impl Values {
    fn type_name(&self) -> &'static str {
        match self {
            Values::F64(_) => "Float64",
            Values::I32(_) => "Int32",
            Values::U64(_) => "UInt64",
            Values::U8(_) => "UInt8",
        }
    }
    /// The size of the values in bytes.
    fn size(&self) -> usize {
        match self {
            Values::F64(v) => 8 * v.len(),
            Values::I32(v) => 4 * v.len(),
            Values::U64(v) => 8 * v.len(),
            Values::U8(v) => v.len(),
        }
    }
    /// The binary payload of the array: with `header`, its size in bytes (UInt64) first;
    /// then the values, little-endian.
    fn payload(&self, header: bool) -> Vec<u8> {
        fn bytes<const K: usize>(
            n: usize,
            header: bool,
            values: impl Iterator<Item = [u8; K]>,
        ) -> Vec<u8> {
            let mut p = Vec::with_capacity(8 + n * K);
            if header {
                p.extend_from_slice(&((n * K) as u64).to_le_bytes());
            }
            for b in values {
                p.extend_from_slice(&b);
            }
            p
        }
        match self {
            Values::F64(v) => bytes(v.len(), header, v.iter().map(|x| x.to_le_bytes())),
            Values::I32(v) => bytes(v.len(), header, v.iter().map(|x| x.to_le_bytes())),
            Values::U64(v) => bytes(v.len(), header, v.iter().map(|x| x.to_le_bytes())),
            Values::U8(v) => bytes(v.len(), header, v.iter().map(|&x| [x])),
        }
    }
    fn as_f64(&self) -> Vec<f64> {
        match self {
            Values::F64(v) => v.clone(),
            Values::I32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            Values::U64(v) => v.iter().map(|&x| x as f64).collect(),
            Values::U8(v) => v.iter().map(|&x| f64::from(x)).collect(),
        }
    }
}

/// One named point-data (or grid) array.
pub(super) struct DataArray {
    pub(super) name: &'static str,
    pub(super) components: usize,
    pub(super) component_names: &'static [&'static str],
    pub(super) values: Values,
}

pub(super) fn array(name: &'static str, components: usize, values: Values) -> DataArray {
    DataArray {
        name,
        components,
        component_names: &[],
        values,
    }
}

/// Field data: strings and numbers describing the whole file.
pub(super) enum FieldValue {
    Text(String),
    Number(f64),
}

/// An unstructured grid: points (x, y, z), cells and the point data.
pub(super) struct Grid {
    pub(super) points: Vec<f64>,
    pub(super) connectivity: Vec<u64>,
    /// The VTK type of every cell, in order; a cell's points follow the previous cell's in
    /// `connectivity` ([`cell_size`]).
    pub(super) cell_types: Vec<u8>,
    pub(super) point_data: Vec<DataArray>,
    /// Attribute names for `<PointData>`: scalars, vectors, tensors.
    pub(super) active: [&'static str; 3],
}

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Appends the base64 encoding of `bytes` (standard alphabet, `=` padding) to `o`.
fn base64_into(o: &mut String, bytes: &[u8]) {
    let mut out = Vec::with_capacity(bytes.len().div_ceil(3) * 4);
    let mut chunks = bytes.chunks_exact(3);
    for c in &mut chunks {
        let n = (u32::from(c[0]) << 16) | (u32::from(c[1]) << 8) | u32::from(c[2]);
        out.extend_from_slice(&[
            B64[(n >> 18) as usize & 63],
            B64[(n >> 12) as usize & 63],
            B64[(n >> 6) as usize & 63],
            B64[n as usize & 63],
        ]);
    }
    let rest = chunks.remainder();
    if !rest.is_empty() {
        let b1 = rest.get(1).copied().unwrap_or(0);
        let n = (u32::from(rest[0]) << 16) | (u32::from(b1) << 8);
        out.extend_from_slice(&[
            B64[(n >> 18) as usize & 63],
            B64[(n >> 12) as usize & 63],
            if rest.len() == 2 {
                B64[(n >> 6) as usize & 63]
            } else {
                b'='
            },
            b'=',
        ]);
    }
    // Every byte comes from the ASCII alphabet above: always valid UTF-8.
    o.push_str(std::str::from_utf8(&out).unwrap_or_default());
}

/// The uncompressed size of a block of compressed data (VTK's default).
const BLOCK_SIZE: usize = 1 << 15;

/// Appends `bytes` as VTK's zlib-compressed inline binary data: the header (UInt64: the
/// number of blocks, the block size, the size of the last block if partial (else 0), the
/// compressed size of each block) in base64, then the blocks, each a zlib stream, in
/// base64 of their own.
fn compressed_into(o: &mut String, bytes: &[u8]) {
    use flate2::{write::ZlibEncoder, Compression};
    use std::io::Write as _;
    let blocks: Vec<Vec<u8>> = bytes
        .chunks(BLOCK_SIZE)
        .map(|block| {
            let mut z = ZlibEncoder::new(Vec::new(), Compression::default());
            // Writing into a Vec cannot fail.
            let _ = z.write_all(block);
            z.finish().unwrap_or_default()
        })
        .collect();
    let mut header: Vec<u64> = vec![
        blocks.len() as u64,
        BLOCK_SIZE as u64,
        (bytes.len() % BLOCK_SIZE) as u64,
    ];
    header.extend(blocks.iter().map(|b| b.len() as u64));
    let header: Vec<u8> = header.iter().flat_map(|h| h.to_le_bytes()).collect();
    base64_into(o, &header);
    base64_into(o, &blocks.concat());
}

fn write_data_array(o: &mut String, a: &DataArray, compressed: bool) {
    let _ = write!(
        o,
        "<DataArray type=\"{}\" Name=\"{}\"",
        a.values.type_name(),
        a.name
    );
    if a.components != 1 {
        let _ = write!(o, " NumberOfComponents=\"{}\"", a.components);
    }
    for (i, c) in a.component_names.iter().enumerate() {
        let _ = write!(o, " ComponentName{i}=\"{c}\"");
    }
    o.push_str(" format=\"binary\"");
    if a.components == 1 {
        let v = a.values.as_f64();
        if !v.is_empty() {
            let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if lo.is_finite() && hi.is_finite() {
                let _ = write!(o, " RangeMin=\"{lo}\" RangeMax=\"{hi}\"");
            }
        }
    }
    o.push('>');
    if compressed {
        compressed_into(o, &a.values.payload(false));
    } else {
        base64_into(o, &a.values.payload(true));
    }
    o.push_str("</DataArray>\n");
}

/// An unstructured grid's XML file: the arrays `style` selects, compressed if it says so.
pub(super) fn grid_xml(
    mut g: Grid,
    meta: &[(&'static str, FieldValue)],
    style: &VtkStyle,
) -> Vec<u8> {
    g.point_data.retain(|a| style.writes(a.name));
    for name in &mut g.active {
        if !style.writes(name) {
            *name = "";
        }
    }
    let z = style.compressed;
    let n_points = g.points.len() / 3;
    let n_cells = g.cell_types.len();
    // The file's size, at most: its base64 payloads and some text (one allocation).
    let payload: usize = g.point_data.iter().map(|a| a.values.size()).sum::<usize>()
        + 8 * (g.points.len() + 2 * g.connectivity.len())
        + n_cells;
    let mut o = String::with_capacity(payload / 3 * 4 + 4096);
    o.push_str(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" \
         byte_order=\"LittleEndian\" header_type=\"UInt64\"",
    );
    if z {
        o.push_str(" compressor=\"vtkZLibDataCompressor\"");
    }
    o.push_str(">\n<UnstructuredGrid>\n<FieldData>\n");
    for (name, v) in meta {
        match v {
            FieldValue::Text(s) => {
                // UTF-8 bytes in a UInt8 array: meshio reads no string arrays.
                if s.is_empty() {
                    continue;
                }
                let codes: Vec<String> = s.bytes().map(|b| b.to_string()).collect();
                let _ = writeln!(
                    o,
                    "<DataArray type=\"UInt8\" Name=\"{name}\" NumberOfTuples=\"{}\" \
                     format=\"ascii\">{}</DataArray>",
                    codes.len(),
                    codes.join(" ")
                );
            }
            FieldValue::Number(x) => {
                let _ = writeln!(
                    o,
                    "<DataArray type=\"Float64\" Name=\"{name}\" NumberOfTuples=\"1\" \
                     format=\"ascii\">{x:?}</DataArray>"
                );
            }
        }
    }
    o.push_str("</FieldData>\n");
    let _ = writeln!(
        o,
        "<Piece NumberOfPoints=\"{n_points}\" NumberOfCells=\"{n_cells}\">"
    );
    let [s, v, t] = g.active;
    let mut attrs = String::new();
    for (key, name) in [("Scalars", s), ("Vectors", v), ("Tensors", t)] {
        if !name.is_empty() {
            let _ = write!(attrs, " {key}=\"{name}\"");
        }
    }
    let _ = writeln!(o, "<PointData{attrs}>");
    for a in &g.point_data {
        write_data_array(&mut o, a, z);
    }
    o.push_str("</PointData>\n<Points>\n");
    write_data_array(&mut o, &array("Points", 3, Values::F64(g.points)), z);
    o.push_str("</Points>\n<Cells>\n");
    // Point indices as Int32 where they fit (a third of a boundary file's bytes otherwise).
    let ends: Vec<usize> = g
        .cell_types
        .iter()
        .scan(0, |end, &c| {
            *end += cell_size(c);
            Some(*end)
        })
        .collect();
    let last_offset = ends.last().copied().unwrap_or(0);
    let (connectivity, offsets) = match (
        g.connectivity
            .iter()
            .map(|&c| i32::try_from(c))
            .collect::<std::result::Result<Vec<i32>, _>>(),
        i32::try_from(last_offset),
    ) {
        (Ok(c), Ok(_)) => (
            Values::I32(c),
            Values::I32(ends.iter().map(|&e| e as i32).collect()),
        ),
        _ => (
            Values::U64(g.connectivity),
            Values::U64(ends.iter().map(|&e| e as u64).collect()),
        ),
    };
    write_data_array(&mut o, &array("connectivity", 1, connectivity), z);
    write_data_array(&mut o, &array("offsets", 1, offsets), z);
    write_data_array(&mut o, &array("types", 1, Values::U8(g.cell_types)), z);
    o.push_str("</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    o.into_bytes()
}

pub(super) const VTK_VERTEX: u8 = 1;
pub(super) const VTK_LINE: u8 = 3;
pub(super) const VTK_TRIANGLE: u8 = 5;

/// The number of points of a cell of VTK type `c` (of those written here).
fn cell_size(c: u8) -> usize {
    match c {
        VTK_VERTEX => 1,
        VTK_LINE => 2,
        _ => 3,
    }
}

#[cfg(test)]
mod tests {
    use super::base64_into;

    #[test]
    fn base64_matches_rfc_4648_vectors() {
        // RFC 4648 §10, appended to text already in the buffer.
        for (input, expected) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            let mut o = String::from(">");
            base64_into(&mut o, input.as_bytes());
            assert_eq!(o, format!(">{expected}"), "{input:?}");
        }
        // Every byte value, through all three positions of a block.
        let bytes: Vec<u8> = (0..=255u8).collect();
        let mut o = String::new();
        base64_into(&mut o, &bytes);
        assert_eq!(o.len(), 344);
        assert!(
            o.starts_with("AAECAwQFBgcICQoLDA0ODxAREhMUFRYXGBkaGxwdHh8g"),
            "{o}"
        );
        assert!(o.ends_with("+/w=="), "{o}");
    }
}
