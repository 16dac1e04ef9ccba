//! The MSH 4.1 reader on the committed gmsh fixtures (`tests/fixtures/two_squares.geo`
//! meshed by gmsh 4.8.4 as ASCII and binary) and on hand-written snippets, one per error
//! class. Truncated and corrupted fixtures must give `Err`, never a panic.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use sgbem::input::mesh::{parse_msh, read_msh, Mesh};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn ascii_bytes() -> Vec<u8> {
    std::fs::read(fixture("two_squares_ascii.msh")).unwrap()
}

fn binary_bytes() -> Vec<u8> {
    std::fs::read(fixture("two_squares_binary.msh")).unwrap()
}

fn parse(text: &str) -> sgbem::error::Result<Mesh> {
    parse_msh(text.as_bytes(), Path::new("snippet.msh"))
}

/// The error message of a snippet that must fail.
fn error_of(text: &str) -> String {
    match parse(text) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => {
            assert_eq!(e.exit_code(), 2, "{e}");
            e.to_string()
        }
    }
}

/// Parses without letting a panic escape; `Err(description)` if the parser panicked.
fn parse_no_panic(bytes: &[u8]) -> Result<sgbem::error::Result<Mesh>, String> {
    catch_unwind(AssertUnwindSafe(|| parse_msh(bytes, Path::new("fuzz.msh"))))
        .map_err(|_| "parser panicked".to_string())
}

#[test]
fn ascii_fixture_matches_the_file() {
    let mesh = read_msh(&fixture("two_squares_ascii.msh")).unwrap();
    assert!(!mesh.binary);
    // $Nodes header "15 24 1 24", $Elements header "10 50 1 50": 1 point element,
    // 6 curves × 2 lines + 3 lines on the transfinite curve 7, 17 + 17 triangles.
    assert_eq!(mesh.nodes.len(), 24);
    assert_eq!(mesh.node_tags, (1..=24).collect::<Vec<_>>());
    assert_eq!(mesh.lines.len(), 15);
    assert_eq!(mesh.triangles.len(), 34);
    assert_eq!(mesh.lines.len() + mesh.triangles.len() + 1, 50);
    assert_eq!(mesh.physical_names.len(), 6);
    assert_eq!(mesh.physical_name(0, 6), Some("corner"));
    assert_eq!(mesh.physical_name(1, 4), Some("interface"));
    assert_eq!(mesh.physical_name(2, 2), Some("right"));
    assert_eq!(mesh.physical_name(2, 3), None);

    assert_eq!(mesh.points.len(), 6);
    assert_eq!(mesh.curves.len(), 7);
    assert_eq!(mesh.surfaces.len(), 2);
    assert_eq!(mesh.points[&1].physical_tags, vec![6]);
    assert!(mesh.points[&2].physical_tags.is_empty());
    // Signed bounding entities, as written in $Entities.
    assert_eq!(mesh.surfaces[&1].bounding, vec![1, 7, 5, 6]);
    assert_eq!(mesh.surfaces[&2].bounding, vec![2, 3, 4, -7]);
    assert_eq!(mesh.surfaces[&2].physical_tags, vec![2]);
    assert_eq!(mesh.curves[&7].bounding, vec![2, -5]);
    assert_eq!(mesh.curves[&7].physical_tags, vec![4]);
    assert_eq!(mesh.curves[&6].physical_tags, vec![3]);

    // The transfinite curve 7 (x = 1) holds 3 lines through nodes 2, 13, 14, 5.
    let on_7: Vec<_> = mesh.lines.iter().filter(|l| l.curve == 7).collect();
    assert_eq!(on_7.len(), 3);
    let tags = |l: &sgbem::input::mesh::Line| l.nodes.map(|i| mesh.node_tags[i]);
    assert_eq!(tags(on_7[0]), [2, 13]);
    assert_eq!(tags(on_7[2]), [14, 5]);
    for line in on_7 {
        for i in line.nodes {
            assert!((mesh.nodes[i][0] - 1.0).abs() < 1e-12);
        }
    }
    let i13 = mesh.node_tags.iter().position(|&t| t == 13).unwrap();
    assert!((mesh.nodes[i13][1] - 1.0 / 3.0).abs() < 1e-11);
    // First triangle of the file: "17 7 2 16" in surface 1.
    let t = mesh.triangles[0];
    assert_eq!((t.tag, t.surface), (17, 1));
    assert_eq!(t.nodes.map(|i| mesh.node_tags[i]), [7, 2, 16]);
    assert!(mesh
        .triangles
        .iter()
        .all(|t| t.surface == 1 || t.surface == 2));
}

#[test]
fn binary_and_ascii_fixtures_agree() {
    let ascii = read_msh(&fixture("two_squares_ascii.msh")).unwrap();
    let binary = read_msh(&fixture("two_squares_binary.msh")).unwrap();
    assert!(binary.binary);
    // gmsh prints 16 significant digits in ASCII: the coordinates agree to round-off.
    assert_eq!(ascii.nodes.len(), binary.nodes.len());
    for (a, b) in ascii.nodes.iter().zip(&binary.nodes) {
        for k in 0..2 {
            assert!(
                (a[k] - b[k]).abs() <= 1e-15 * (1.0 + a[k].abs()),
                "{a:?} {b:?}"
            );
        }
    }
    let same = Mesh {
        binary: false,
        nodes: ascii.nodes.clone(),
        ..binary
    };
    assert_eq!(same, ascii);
}

#[test]
fn binary_parametric_coordinates_are_skipped() {
    // Same mesh saved with Mesh.SaveParametric = 1: u after the curve nodes, u v after
    // the surface nodes.
    let plain = read_msh(&fixture("two_squares_binary.msh")).unwrap();
    let parametric = read_msh(&fixture("two_squares_param_binary.msh")).unwrap();
    assert_eq!(parametric, plain);
}

#[test]
fn missing_file_is_an_io_error() {
    let err = read_msh(Path::new("tests/fixtures/no_such_file.msh")).unwrap_err();
    assert_eq!(err.exit_code(), 1);
}

#[test]
fn every_truncation_of_the_fixtures_is_an_error() {
    let parametric = std::fs::read(fixture("two_squares_param_binary.msh")).unwrap();
    for bytes in [ascii_bytes(), binary_bytes(), parametric] {
        // Dropping only the final newline leaves a complete file.
        for cut in 0..bytes.len() - 1 {
            match parse_no_panic(&bytes[..cut]) {
                Err(p) => panic!("cut at {cut}: {p}"),
                Ok(Ok(_)) => panic!("cut at {cut} parsed as a whole mesh"),
                Ok(Err(e)) => assert_eq!(e.exit_code(), 2),
            }
        }
        assert!(parse_msh(&bytes[..bytes.len() - 1], Path::new("x")).is_ok());
    }
}

#[test]
fn truncation_errors_name_the_section_and_position() {
    let ascii = ascii_bytes();
    let text = String::from_utf8(ascii.clone()).unwrap();
    let cut = text.find("$EndNodes").unwrap() - 20;
    let message = parse_msh(&ascii[..cut], Path::new("a.msh"))
        .unwrap_err()
        .to_string();
    assert!(message.contains("in $Nodes at line"), "{message}");
    assert!(message.contains("end of file"), "{message}");

    let binary = binary_bytes();
    let at = binary.windows(9).position(|w| w == b"$EndNodes").unwrap() - 40;
    let message = parse_msh(&binary[..at], Path::new("b.msh"))
        .unwrap_err()
        .to_string();
    assert!(message.contains("in $Nodes at byte"), "{message}");
}

/// A small deterministic generator, so that the corruption tests need no dependency.
struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

#[test]
fn corrupted_bytes_never_panic() {
    let values = [
        0x00, 0xff, 0x80, b'0', b'9', b'-', b' ', b'\n', b'$', b'"', b'e',
    ];
    for bytes in [ascii_bytes(), binary_bytes()] {
        for pos in 0..bytes.len() {
            for &v in &values {
                let mut corrupt = bytes.clone();
                corrupt[pos] = v;
                if let Err(p) = parse_no_panic(&corrupt) {
                    panic!("byte {pos} set to {v:#x}: {p}");
                }
            }
        }
        // Several random bytes at once, and random cuts of the corrupted file.
        let mut rng = XorShift(0x9e37_79b9_7f4a_7c15);
        for round in 0..3000 {
            let mut corrupt = bytes.clone();
            for _ in 0..1 + rng.next() % 8 {
                let pos = (rng.next() % corrupt.len() as u64) as usize;
                corrupt[pos] = rng.next() as u8;
            }
            if round % 3 == 0 {
                corrupt.truncate((rng.next() % corrupt.len() as u64) as usize);
            }
            if let Err(p) = parse_no_panic(&corrupt) {
                panic!("round {round}: {p}");
            }
        }
    }
}

#[test]
fn huge_counts_in_binary_are_refused_before_allocating() {
    let bytes = binary_bytes();
    // The number of nodes follows the number of node blocks right after "$Nodes\n".
    let at = bytes.windows(7).position(|w| w == b"$Nodes\n").unwrap() + 7 + 8;
    for huge in [u64::MAX, 1 << 40, 1 << 20] {
        let mut corrupt = bytes.clone();
        corrupt[at..at + 8].copy_from_slice(&huge.to_le_bytes());
        let message = parse_msh(&corrupt, Path::new("b.msh"))
            .unwrap_err()
            .to_string();
        assert!(message.contains("$Nodes"), "{message}");
    }
}

/// A valid hand-written mesh: one triangle (surface 1) bounded by curves 1, 2, 3, with
/// one 2-node line on curve 1.
const BASE: &str = "\
$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
2
1 1 \"bottom edge\"
2 2 \"body\"
$EndPhysicalNames
$Entities
1 3 1 0
1 0 0 0 0
1 0 0 0 1 0 0 1 1 2 1 -2
2 0 0 0 1 1 0 0 0
3 0 0 0 1 1 0 0 0
1 0 0 0 1 1 0 1 2 3 1 2 -3
$EndEntities
$Nodes
2 3 1 3
1 1 0 2
1
2
0 0 0
1 0 0
2 1 0 1
3
0 1 0
$EndNodes
$Elements
2 2 1 2
1 1 1 1
1 1 2
2 1 2 1
2 1 2 3
$EndElements
";

fn base_with(from: &str, to: &str) -> String {
    assert!(BASE.contains(from), "{from}");
    BASE.replacen(from, to, 1)
}

#[test]
fn hand_written_base_mesh_parses() {
    let mesh = parse(BASE).unwrap();
    assert_eq!(mesh.nodes, vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
    assert_eq!(mesh.physical_name(1, 1), Some("bottom edge"));
    assert_eq!(mesh.lines.len(), 1);
    assert_eq!(mesh.lines[0].nodes, [0, 1]);
    assert_eq!(mesh.triangles[0].nodes, [0, 1, 2]);
    assert_eq!(mesh.surfaces[&1].bounding, vec![1, 2, -3]);
    assert_eq!(mesh.curves[&1].bounding, vec![1, -2]);
    // Windows line endings are whitespace like any other.
    assert_eq!(parse(&BASE.replace('\n', "\r\n")).unwrap(), mesh);
}

#[test]
fn other_format_versions_are_refused_with_the_fix() {
    for version in ["2.2", "4", "4.0", "3.0", "41"] {
        let message = error_of(&base_with("4.1 0 8", &format!("{version} 0 8")));
        assert!(message.contains("gmsh -format msh41"), "{message}");
        assert!(message.contains(version), "{message}");
    }
    let message = error_of(&base_with("4.1 0 8", "four 0 8"));
    assert!(message.contains("version"), "{message}");
    let message = error_of(&base_with("4.1 0 8", "4.1 2 8"));
    assert!(message.contains("file type 2"), "{message}");
    let message = error_of(&base_with("4.1 0 8", "4.1 0 4"));
    assert!(message.contains("data size 4"), "{message}");
    let message = error_of("$NOD\n3\n$ENDNOD\n");
    assert!(message.contains("gmsh -format msh41"), "{message}");
    let message = error_of("solid cube\nendsolid\n");
    assert!(message.contains("$MeshFormat"), "{message}");
    for empty in ["", " \n\n"] {
        assert!(error_of(empty).contains("empty"));
    }
}

#[test]
fn binary_endianness_is_checked() {
    let mut bytes = b"$MeshFormat\n4.1 1 8\n".to_vec();
    bytes.extend_from_slice(&1i32.to_be_bytes());
    bytes.extend_from_slice(b"\n$EndMeshFormat\n");
    let message = parse_msh(&bytes, Path::new("be.msh"))
        .unwrap_err()
        .to_string();
    assert!(message.contains("endianness"), "{message}");
    assert!(message.contains("$MeshFormat"), "{message}");
}

#[test]
fn volumes_are_refused() {
    let message = error_of(&base_with("1 3 1 0\n", "1 3 1 1\n"));
    assert!(message.contains("3D mesh: sgbem is 2D"), "{message}");
    assert!(message.contains("$Entities"), "{message}");
}

#[test]
fn partitioned_meshes_are_refused() {
    let text = base_with(
        "$Nodes",
        "$PartitionedEntities\n2\n0\n0 0 0 0\n$EndPartitionedEntities\n$Nodes",
    );
    let message = error_of(&text);
    assert!(message.contains("$PartitionedEntities"), "{message}");
    assert!(message.contains("partitioned"), "{message}");
}

#[test]
fn unknown_sections_are_skipped() {
    let text = base_with(
        "$Entities",
        "$Comments\nnot a $Nodes section 1 2 3\n$EndComments\n$Entities",
    );
    let mut more = text.clone();
    more.push_str(
        "$NodeData\n1\n\"u\"\n1\n0.0\n3\n0\n1\n3\n1 0.5\n2 0.5\n3 0.5\n$EndNodeData\n\
         $Periodic\n0\n$EndPeriodic\n",
    );
    assert_eq!(parse(&more).unwrap(), parse(BASE).unwrap());

    let message = error_of(&base_with(
        "$Entities",
        "$Comments\nnever closed\n$Entities",
    ));
    assert!(message.contains("$EndComments"), "{message}");
}

#[test]
fn misplaced_end_markers_and_bad_headers_are_errors() {
    let message = error_of(&base_with("$EndEntities\n", "$EndEntities\n$EndNodes\n"));
    assert!(message.contains("$EndNodes"), "{message}");
    let message = error_of(&base_with("$Entities", "garbage\n$Entities"));
    assert!(
        message.contains("garbage") && message.contains("line 9"),
        "{message}"
    );
    let message = error_of(&format!("{BASE}$Nodes\n0 0 0 0\n$EndNodes\n"));
    assert!(message.contains("second $Nodes"), "{message}");
}

#[test]
fn missing_sections_are_errors() {
    let without_elements = &BASE[..BASE.find("$Elements").unwrap()];
    let message = error_of(without_elements);
    assert!(message.contains("no $Elements section"), "{message}");
    let message = error_of("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    assert!(message.contains("no $Entities section"), "{message}");
}

#[test]
fn counts_that_disagree_with_the_content_are_errors() {
    // One more physical name declared than written.
    let message = error_of(&base_with("$PhysicalNames\n2\n", "$PhysicalNames\n3\n"));
    assert!(message.contains("$PhysicalNames"), "{message}");
    // Header total smaller than the blocks.
    let message = error_of(&base_with("2 3 1 3\n", "2 2 1 3\n"));
    assert!(message.contains("$Nodes") && message.contains("more than the 2 nodes"));
    // Header total larger than the blocks.
    let message = error_of(&base_with("2 3 1 3\n", "2 4 1 3\n"));
    assert!(
        message.contains("declares 4 nodes but the blocks hold 3"),
        "{message}"
    );
    let message = error_of(&base_with("2 2 1 2\n", "2 3 1 2\n"));
    assert!(message.contains("declares 3 elements"), "{message}");
    // A block holding fewer nodes than its data: the leftover is not $EndNodes.
    let message = error_of(&base_with("2 1 0 1\n3\n", "2 1 0 0\n3\n"));
    assert!(message.contains("$Nodes"), "{message}");
    // Absurd counts are refused before anything is allocated.
    let message = error_of(&base_with("2 3 1 3\n", "2 18446744073709551615 1 3\n"));
    assert!(
        message.contains("18446744073709551615 nodes declared"),
        "{message}"
    );
    let message = error_of(&base_with("1 3 1 0\n", "1 99999999999 1 0\n"));
    assert!(message.contains("$Entities"), "{message}");
}

#[test]
fn unsupported_element_types_name_the_type_the_entity_and_the_fix() {
    let message = error_of(&base_with("1 1 1 1\n1 1 2\n", "1 1 8 1\n1 1 2 3\n"));
    assert!(message.contains("element type 8"), "{message}");
    assert!(message.contains("tag 1"), "{message}");
    assert!(message.contains("-order 1"), "{message}");

    let message = error_of(&base_with("2 1 2 1\n2 1 2 3\n", "2 1 3 1\n2 1 2 3 3\n"));
    assert!(message.contains("element type 3"), "{message}");
    assert!(message.contains("Recombine"), "{message}");

    let message = error_of(&base_with("2 1 2 1\n2 1 2 3\n", "2 1 9 1\n2 1 2 3 3 3 3\n"));
    assert!(message.contains("element type 9") && message.contains("-order 1"));

    let message = error_of(&base_with("2 1 2 1\n2 1 2 3\n", "3 1 4 1\n2 1 2 3 3\n"));
    assert!(
        message.contains("element type 4") && message.contains("3D"),
        "{message}"
    );

    let message = error_of(&base_with("2 1 2 1\n2 1 2 3\n", "2 1 77 1\n2 1\n"));
    assert!(message.contains("element type 77"), "{message}");
}

#[test]
fn elements_must_lie_on_entities_of_their_dimension() {
    // A line block in a surface.
    let message = error_of(&base_with("1 1 1 1\n1 1 2\n", "2 1 1 1\n1 1 2\n"));
    assert!(message.contains("not a curve"), "{message}");
    // A line block on a curve missing from $Entities.
    let message = error_of(&base_with("1 1 1 1\n1 1 2\n", "1 9 1 1\n1 1 2\n"));
    assert!(message.contains("tag 9"), "{message}");
    // A triangle block on a curve.
    let message = error_of(&base_with("2 1 2 1\n2 1 2 3\n", "1 1 2 1\n2 1 2 3\n"));
    assert!(message.contains("not a surface"), "{message}");
    // Points (type 15) are read and ignored.
    let text = base_with("2 2 1 2\n", "3 3 1 3\n0 1 15 1\n3 1\n");
    assert_eq!(parse(&text).unwrap(), parse(BASE).unwrap());
}

#[test]
fn elements_must_refer_to_existing_nodes() {
    let message = error_of(&base_with("2 1 2 3\n$EndElements", "2 1 2 7\n$EndElements"));
    assert!(message.contains("element 2 refers to node 7"), "{message}");
    assert!(message.contains("$Elements at line"), "{message}");
    let text = base_with(
        "2 2 1 2\n1 1 1 1\n1 1 2\n",
        "2 3 1 2\n1 1 1 2\n1 1 2\n1 2 3\n",
    );
    let message = error_of(&text);
    assert!(message.contains("duplicate element tag 1"), "{message}");
}

#[test]
fn node_errors_name_the_node() {
    let message = error_of(&base_with("2 1 0 1\n3\n", "2 1 0 1\n2\n"));
    assert!(message.contains("duplicate node tag 2"), "{message}");
    assert!(message.contains("$Nodes at line 25"), "{message}");

    let message = error_of(&base_with("0 1 0\n$EndNodes", "0 1 0.5\n$EndNodes"));
    assert!(message.contains("node 3"), "{message}");
    assert!(
        message.contains("sgbem is 2D: draw in the z = 0 plane"),
        "{message}"
    );

    // Round-off in z relative to the size of the drawing is accepted.
    let text = base_with("0 1 0\n$EndNodes", "0 1000 1e-8\n$EndNodes");
    assert!(parse(&text).is_ok());
    let text = base_with("0 1 0\n$EndNodes", "0 1000 1e-5\n$EndNodes");
    assert!(error_of(&text).contains("node 3"));

    for bad in ["nan", "inf", "-inf", "1e400"] {
        let message = error_of(&base_with("1 0 0\n", &format!("1 {bad} 0\n")));
        assert!(message.contains("node 2"), "{bad}: {message}");
        assert!(message.contains("non-finite"), "{bad}: {message}");
    }

    let message = error_of(&base_with("1 0 0\n", "1 zero 0\n"));
    assert!(message.contains("in $Nodes at line 23"), "{message}");
    assert!(message.contains("y coordinate"), "{message}");
    assert!(message.contains("'zero'"), "{message}");

    let message = error_of(&base_with("2 1 0 1\n", "2 1 0 -1\n"));
    assert!(message.contains("non-negative"), "{message}");
    let message = error_of(&base_with("2 1 0 1\n", "2 1 2 1\n"));
    assert!(message.contains("parametric flag 2"), "{message}");
    let message = error_of(&base_with("2 1 0 1\n", "3 1 0 1\n"));
    assert!(message.contains("3D mesh"), "{message}");
    let message = error_of(&base_with("2 1 0 1\n3\n", "2 1 0 1\n0\n"));
    assert!(message.contains("node tag 0"), "{message}");
}

#[test]
fn parametric_coordinates_are_skipped() {
    let text = base_with(
        "1 1 0 2\n1\n2\n0 0 0\n1 0 0\n2 1 0 1\n3\n0 1 0\n",
        "1 1 1 2\n1\n2\n0 0 0 0.0\n1 0 0 1.0\n2 1 1 1\n3\n0 1 0 0.25 0.75\n",
    );
    assert_eq!(parse(&text).unwrap(), parse(BASE).unwrap());
}

#[test]
fn non_utf8_text_is_an_error() {
    let mut bytes = base_with("1 0 0\n", "1 \u{e9}0 0\n").into_bytes();
    // Replace the two-byte UTF-8 é by a lone Latin-1 byte.
    let at = bytes
        .windows(2)
        .position(|w| w == "\u{e9}".as_bytes())
        .unwrap();
    bytes.splice(at..at + 2, [0xe9]);
    let message = parse_msh(&bytes, Path::new("l1.msh"))
        .unwrap_err()
        .to_string();
    assert!(message.contains("$Nodes"), "{message}");

    let mut bytes = BASE.as_bytes().to_vec();
    let at = bytes.windows(6).position(|w| w == b"bottom").unwrap();
    bytes[at] = 0xff;
    let message = parse_msh(&bytes, Path::new("l1.msh"))
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("UTF-8") && message.contains("$PhysicalNames"),
        "{message}"
    );
}

#[test]
fn physical_names_must_be_quoted() {
    let message = error_of(&base_with("2 2 \"body\"", "2 2 body"));
    assert!(message.contains("quoted"), "{message}");
    let message = error_of(&base_with("2 2 \"body\"", "2 2 \"body"));
    assert!(message.contains("closing quote"), "{message}");
}

#[test]
fn duplicate_entities_are_errors() {
    let message = error_of(&base_with("3 0 0 0 1 1 0 0 0\n", "2 0 0 0 1 1 0 0 0\n"));
    assert!(message.contains("duplicate curve tag 2"), "{message}");
}
