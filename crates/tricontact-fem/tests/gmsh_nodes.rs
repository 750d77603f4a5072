//! Node tags are honoured wherever they are in the file: a mesh whose dense tags are not in file
//! order (two nodes swapped, tags and coordinates together) is the same mesh, ASCII and binary;
//! a tag defined twice and a non-finite coordinate are errors naming the node.

use std::path::{Path, PathBuf};

use tricontact_fem::gmsh::parse_msh;
use tricontact_fem::mesh::Mesh;

fn file(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Coordinates by node tag.
fn by_tag(mesh: &Mesh) -> Vec<(u64, [f64; 3])> {
    let mut v: Vec<_> = mesh
        .node_tags
        .iter()
        .copied()
        .zip(mesh.nodes.iter().copied())
        .collect();
    v.sort_by_key(|p| p.0);
    v
}

/// Element connectivity as node tags.
fn connectivity(mesh: &Mesh) -> Vec<Vec<u64>> {
    mesh.elements
        .iter()
        .map(|e| e.nodes.iter().map(|&i| mesh.node_tags[i]).collect())
        .collect()
}

/// The same nodes by tag and the same elements by node tag.
fn assert_same_mesh(a: &Mesh, b: &Mesh) {
    assert_eq!(by_tag(a), by_tag(b));
    assert_eq!(connectivity(a), connectivity(b));
}

/// The ASCII mesh with the tag lines and coordinate lines of the first two nodes of its first
/// block of several nodes swapped.
fn swap_ascii(text: &str) -> String {
    let mut lines: Vec<&str> = text.lines().collect();
    let mut at = lines.iter().position(|l| *l == "$Nodes").expect("$Nodes") + 2;
    loop {
        let n: usize = lines[at]
            .split_whitespace()
            .nth(3)
            .expect("block")
            .parse()
            .expect("n");
        if n >= 2 {
            lines.swap(at + 1, at + 2);
            lines.swap(at + 1 + n, at + 2 + n);
            break;
        }
        at += 1 + 2 * n;
    }
    lines.join("\n") + "\n"
}

/// The binary mesh (size_t of 8 bytes) with the first two nodes of its first block of several
/// nodes swapped, tags and coordinates.
fn swap_binary(bytes: &[u8]) -> Vec<u8> {
    let mut out = bytes.to_vec();
    let marker = b"\n$Nodes\n";
    let mut at = bytes
        .windows(marker.len())
        .position(|w| w == marker)
        .expect("$Nodes")
        + marker.len()
        + 32;
    let word = |b: &[u8], at: usize| u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"));
    loop {
        let n = usize::try_from(word(bytes, at + 12)).expect("n");
        let tags = at + 20;
        if n >= 2 {
            let coords = tags + 8 * n;
            for (a, b, len) in [(tags, tags + 8, 8), (coords, coords + 24, 24)] {
                let first = bytes[a..a + len].to_vec();
                out.copy_within(b..b + len, a);
                out[b..b + len].copy_from_slice(&first);
            }
            return out;
        }
        at = tags + 32 * n;
    }
}

#[test]
fn tags_out_of_file_order_are_honoured_in_ascii() {
    let path = file("../../examples/cantilever/beam.msh");
    let text = std::fs::read_to_string(&path).expect("beam.msh");
    let original = parse_msh(text.as_bytes(), &path).expect("original");
    let swapped_text = swap_ascii(&text);
    assert_ne!(swapped_text, text);
    let swapped = parse_msh(swapped_text.as_bytes(), &path).expect("swapped");
    assert_ne!(swapped.nodes, original.nodes, "the file order changed");
    assert_same_mesh(&swapped, &original);
}

#[test]
fn binary_mesh_reads_as_its_ascii_twin_also_with_tags_out_of_order() {
    let ascii = file("../../examples/cantilever/beam.msh");
    let original = parse_msh(&std::fs::read(&ascii).expect("ascii"), &ascii).expect("ascii");
    let path = file("tests/data/beam-binary.msh");
    let bytes = std::fs::read(&path).expect("binary");
    let binary = parse_msh(&bytes, &path).expect("binary");
    assert_same_mesh(&binary, &original);
    let swapped = parse_msh(&swap_binary(&bytes), &path).expect("swapped");
    assert_ne!(swapped.nodes, binary.nodes, "the file order changed");
    assert_same_mesh(&swapped, &original);
}

#[test]
fn a_tag_defined_twice_or_a_non_finite_coordinate_is_named() {
    let path = file("../../examples/cantilever/beam.msh");
    let text = std::fs::read_to_string(&path).expect("beam.msh");
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let at = lines.iter().position(|l| l == "$Nodes").expect("$Nodes") + 2;
    // First block: one node (a corner point); its tag line and coordinate line follow.
    let tag: u64 = lines[at + 1].trim().parse().expect("tag");
    let mut nan = lines.clone();
    nan[at + 2] = "nan 0 0".into();
    let e = parse_msh((nan.join("\n") + "\n").as_bytes(), &path).expect_err("nan");
    assert!(
        e.to_string()
            .contains(&format!("node {tag} has a non-finite coordinate")),
        "{e}"
    );
    // The second node block's first tag made equal to the first node's.
    let n: usize = lines[at]
        .split_whitespace()
        .nth(3)
        .expect("n")
        .parse()
        .expect("n");
    let second = at + 1 + 2 * n;
    lines[second + 1] = tag.to_string();
    let e = parse_msh((lines.join("\n") + "\n").as_bytes(), &path).expect_err("duplicate");
    assert!(
        e.to_string()
            .contains(&format!("node tag {tag} is defined twice")),
        "{e}"
    );
}

#[test]
fn a_duplicate_element_tag_or_a_missing_elements_section_is_named() {
    let path = file("../../examples/cantilever/beam.msh");
    let text = std::fs::read_to_string(&path).expect("beam.msh");
    // The first block's second element (tag 2) takes the first one's tag.
    let duplicate = text.replacen("\n2 12 93 11 4 \n", "\n1 12 93 11 4 \n", 1);
    assert_ne!(duplicate, text);
    let e = parse_msh(duplicate.as_bytes(), &path).expect_err("duplicate tag");
    assert!(
        e.to_string().contains("element tag 1 is defined twice"),
        "{e}"
    );
    let cut = &text[..text.find("$Elements").expect("$Elements")];
    let e = parse_msh(cut.as_bytes(), &path).expect_err("no elements");
    assert!(e.to_string().contains("no $Elements section"), "{e}");
}
