//! Gmsh `.msh` 4.1 reader (ASCII and binary) built on the `mshio` crate.
//!
//! `mshio` parses entities, nodes and elements but skips `$PhysicalNames`, so
//! that short (always ASCII) section is read here: lines `dim tag "name"`.
//! An element block belongs to a geometric entity `(dim, tag)`; the entity
//! lists its physical tags, and each `(dim, physical tag)` is one named
//! [`Group`]. Unnamed groups are named by their tag number.
//!
//! Node tags: when the file's node tags are dense, `mshio` does not return
//! them; they are read from the file by [`crate::gmsh_nodes`], so a mesh whose
//! tags are not in file order is read right. A tag defined twice and a
//! non-finite coordinate are errors naming the node.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use mshio::mshfile::ElementType;

use crate::error::{FemError, Result};
use crate::mesh::{Element, ElementKind, Group, Mesh};

/// Reads a Gmsh 4.1 mesh file.
///
/// # Errors
/// I/O errors, parse errors, unsupported element types in a physical group.
pub fn read_msh(path: &Path) -> Result<Mesh> {
    // A device or a pipe (`/dev/zero`) would be read until memory runs out.
    let meta = std::fs::metadata(path).map_err(|e| FemError::io(path, e))?;
    if !meta.is_file() {
        return Err(FemError::Mesh {
            path: path.to_path_buf(),
            message: "not a regular file (a mesh is a .msh file)".into(),
        });
    }
    let bytes = std::fs::read(path).map_err(|e| FemError::io(path, e))?;
    parse_msh(&bytes, path)
}

/// `", reading stopped at line N"` (an ASCII file) or `"… at byte N"` (a binary one): the
/// position of `rest`, a slice of `bytes` (`None` when it is not one). The parser reads numbers
/// across line breaks, so a short line shows where reading ran out, below it. The version line
/// `4.1 <file-type> <size>` tells the file type.
fn place(bytes: &[u8], rest: &[u8], version_line: &str) -> Option<String> {
    let offset = (rest.as_ptr() as usize).checked_sub(bytes.as_ptr() as usize)?;
    let before = bytes.get(..offset)?;
    if version_line.split_whitespace().nth(1) == Some("0") {
        let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
        Some(format!(", reading stopped at line {line}"))
    } else {
        Some(format!(", reading stopped at byte {offset}"))
    }
}

/// Parses the `$PhysicalNames` section: `(dim, tag) -> name`.
///
/// # Errors
/// A malformed section.
pub fn parse_physical_names(bytes: &[u8], path: &Path) -> Result<HashMap<(i32, i32), String>> {
    let mut names = HashMap::new();
    let Some(start) = find(bytes, b"$PhysicalNames") else {
        return Ok(names);
    };
    let rest = &bytes[start + b"$PhysicalNames".len()..];
    let end = find(rest, b"$EndPhysicalNames").ok_or_else(|| FemError::Mesh {
        path: path.to_path_buf(),
        message: "$PhysicalNames without $EndPhysicalNames".into(),
    })?;
    let text = String::from_utf8_lossy(&rest[..end]);
    let bad = |line: &str| FemError::Mesh {
        path: path.to_path_buf(),
        message: format!("malformed $PhysicalNames line '{line}'"),
    };
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let count: usize = lines
        .next()
        .and_then(|l| l.parse().ok())
        .ok_or_else(|| bad("<count>"))?;
    let mut by_name: HashMap<(i32, String), i32> = HashMap::new();
    let mesh_error = |message: String| FemError::Mesh {
        path: path.to_path_buf(),
        message,
    };
    for k in 0..count {
        let line = lines.next().ok_or_else(|| {
            mesh_error(format!(
                "$PhysicalNames announces {count} names but lists {k}"
            ))
        })?;
        let mut it = line.splitn(3, char::is_whitespace);
        let dim: i32 = it
            .next()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| bad(line))?;
        let tag: i32 = it
            .next()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| bad(line))?;
        let name = it.next().ok_or_else(|| bad(line))?.trim().trim_matches('"');
        if let Some(other) = by_name.insert((dim, name.to_string()), tag) {
            return Err(mesh_error(format!(
                "physical name '{name}' is given to two {dim}D groups (tags {other} and {tag}); \
                 a name must be unique within a dimension"
            )));
        }
        if names.insert((dim, tag), name.to_string()).is_some() {
            return Err(mesh_error(format!(
                "the {dim}D physical group {tag} is named twice in $PhysicalNames"
            )));
        }
    }
    if let Some(extra) = lines.next() {
        return Err(mesh_error(format!(
            "$PhysicalNames announces {count} names but lists more (first extra line '{extra}')"
        )));
    }
    Ok(names)
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

fn kind_of(t: ElementType) -> Option<ElementKind> {
    Some(match t {
        ElementType::Tet4 => ElementKind::Tet4,
        ElementType::Tet10 => ElementKind::Tet10,
        ElementType::Hex8 => ElementKind::Hex8,
        ElementType::Tri3 => ElementKind::Tri3,
        ElementType::Tri6 => ElementKind::Tri6,
        ElementType::Qua4 => ElementKind::Quad4,
        _ => return None,
    })
}

/// Largest coordinate magnitude accepted: element volumes (cubes of lengths) stay finite.
pub const MAX_COORDINATE: f64 = 1e100;

/// What is wrong with a node's coordinates, if anything: one that is not finite, or one beyond
/// ±[`MAX_COORDINATE`]. The reader and [`crate::mesh::Mesh::check`] apply the same rule.
#[must_use]
pub fn coordinate_fault(x: &[f64; 3]) -> Option<String> {
    if !x.iter().all(|c| c.is_finite()) {
        return Some(format!(
            "a non-finite coordinate ({}, {}, {})",
            x[0], x[1], x[2]
        ));
    }
    // Volumes are cubes of lengths: beyond this they overflow.
    x.iter().any(|c| c.abs() > MAX_COORDINATE).then(|| {
        format!(
            "a coordinate beyond ±{MAX_COORDINATE:e} ({:e}, {:e}, {:e})",
            x[0], x[1], x[2]
        )
    })
}

/// Parses the bytes of a `.msh` file (`path` is used in messages only).
///
/// # Errors
/// See [`read_msh`].
pub fn parse_msh(bytes: &[u8], path: &Path) -> Result<Mesh> {
    let merr = |message: String| FemError::Mesh {
        path: path.to_path_buf(),
        message,
    };
    // A byte-order mark, as some editors write: not part of the format.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let version_line = version(bytes).map_err(merr)?;
    let names = parse_physical_names(bytes, path)?;
    let msh = mshio::parse_msh_bytes(bytes)
        .map_err(|e| merr(parse_error_message(&e, bytes, &version_line)))?;
    let mut mesh = Mesh::default();
    let tag_to_index = read_nodes(&msh, bytes, &mut mesh).map_err(merr)?;
    mesh.groups = read_elements(&msh, &names, &tag_to_index, &mut mesh, path)?;
    Ok(mesh)
}

/// The version line of a `.msh` file (its second line), or why the file cannot be read: not a
/// Gmsh file, or not of format 4.1.
fn version(bytes: &[u8]) -> std::result::Result<String, String> {
    if !bytes.starts_with(b"$MeshFormat") {
        return Err("not a Gmsh mesh file (no $MeshFormat header)".into());
    }
    let version_line = bytes
        .split(|&b| b == b'\n')
        .nth(1)
        .map(|l| String::from_utf8_lossy(l).trim().to_string())
        .unwrap_or_default();
    if !version_line.starts_with("4.1") {
        return Err(format!(
            "only MSH format 4.1 is supported, found '{version_line}' (export with Mesh.MshFileVersion = 4.1)"
        ));
    }
    Ok(version_line)
}

/// `mshio`'s parse error `e` on `bytes` as one line: its context chain without the hex dump, where
/// the innermost parser stopped, and which section never ends when the file was cut off.
fn parse_error_message(
    e: &mshio::MshParserError<&[u8]>,
    bytes: &[u8],
    version_line: &str,
) -> String {
    // mshio's message spans several lines and ends with a hex dump: keep
    // the context chain on one line.
    let text = e.to_string();
    let text = text.split("Hex dump").next().unwrap_or_default();
    // A cut-off file is the usual cause: say which section never ends.
    let unfinished = ["$Entities", "$Nodes", "$Elements"].into_iter().find(|s| {
        find(bytes, s.as_bytes()).is_some()
            && find(bytes, format!("$End{}", &s[1..]).as_bytes()).is_none()
    });
    // mshio's catch-all, met where a section holds more or fewer lines than its headers count
    // (a line repeated or dropped): the place is where reading stopped, at or after that line.
    let catch_all = text.contains("Unknown error occurred");
    let hint = unfinished
        .map(|s| format!(" (the file ends inside {s}: is it complete?)"))
        .or_else(|| {
            catch_all.then(|| {
                " (at or before that line a section holds more or fewer lines than its headers \
                 count: a line repeated or missing?)"
                    .to_string()
            })
        })
        .unwrap_or_default();
    // Where the innermost parser stopped (its input is a slice of `bytes`).
    let place = e
        .backtrace
        .first()
        .and_then(|(rest, _)| place(bytes, rest, version_line))
        .unwrap_or_default();
    format!(
        "parse error{place}: {}{hint}",
        text.split_whitespace().collect::<Vec<_>>().join(" ")
    )
}

/// The parsed file's type.
type MshFile = mshio::MshFile<u64, i32, f64>;
type ElementBlock = mshio::mshfile::ElementBlock<u64, i32>;

/// The physical tags of each entity `(dim, tag)`.
fn physical_tags_of_entities(msh: &MshFile) -> HashMap<(i32, i32), Vec<i32>> {
    let mut entity_phys: HashMap<(i32, i32), Vec<i32>> = HashMap::new();
    if let Some(ent) = &msh.data.entities {
        for p in &ent.points {
            entity_phys.insert((0, p.tag), p.physical_tags.clone());
        }
        for c in &ent.curves {
            entity_phys.insert((1, c.tag), c.physical_tags.clone());
        }
        for s in &ent.surfaces {
            entity_phys.insert((2, s.tag), s.physical_tags.clone());
        }
        for v in &ent.volumes {
            entity_phys.insert((3, v.tag), v.physical_tags.clone());
        }
    }
    entity_phys
}

/// The nodes of `msh` into `mesh` (coordinates and tags, the tags read from `bytes` when the file
/// holds them; see the module documentation); returns each tag's index.
fn read_nodes(
    msh: &MshFile,
    bytes: &[u8],
    mesh: &mut Mesh,
) -> std::result::Result<HashMap<u64, usize>, String> {
    let mut tag_to_index: HashMap<u64, usize> = HashMap::new();
    if let Some(nodes) = &msh.data.nodes {
        let total: usize = nodes.node_blocks.iter().map(|b| b.nodes.len()).sum();
        if usize::try_from(nodes.num_nodes).ok() != Some(total) {
            return Err(format!(
                "the $Nodes header counts {} nodes but its blocks hold {total}",
                nodes.num_nodes
            ));
        }
        let mut file_tags = crate::gmsh_nodes::node_tags(bytes)
            .filter(|t| t.len() == total)
            .map(Vec::into_iter);
        let mut next_dense = nodes.min_node_tag;
        for block in &nodes.node_blocks {
            let mut block_tags = vec![0u64; block.nodes.len()];
            match (&mut file_tags, &block.node_tags) {
                (Some(tags), _) => {
                    for (slot, tag) in block_tags.iter_mut().zip(tags) {
                        *slot = tag;
                    }
                }
                (None, Some(map)) => {
                    for (&tag, &i) in map {
                        if let Some(slot) = block_tags.get_mut(i) {
                            *slot = tag;
                        }
                    }
                }
                (None, None) => {
                    for t in &mut block_tags {
                        *t = next_dense;
                        next_dense += 1;
                    }
                }
            }
            for (node, tag) in block.nodes.iter().zip(block_tags) {
                let x = [node.x, node.y, node.z];
                if let Some(fault) = coordinate_fault(&x) {
                    return Err(format!("node {tag} has {fault}"));
                }
                if tag_to_index.insert(tag, mesh.nodes.len()).is_some() {
                    return Err(format!("node tag {tag} is defined twice"));
                }
                mesh.nodes.push(x);
                mesh.node_tags.push(tag);
            }
        }
    }
    if mesh.nodes.is_empty() {
        return Err("the mesh has no nodes".into());
    }
    Ok(tag_to_index)
}

/// The elements of `msh` into `mesh` (those of physical groups; points and lines only give their
/// nodes to their groups), and the groups keyed by `(dim, physical tag)`, named from `names` (by
/// their tag otherwise), named groups without elements included.
fn read_elements(
    msh: &MshFile,
    names: &HashMap<(i32, i32), String>,
    tag_to_index: &HashMap<u64, usize>,
    mesh: &mut Mesh,
    path: &Path,
) -> Result<Vec<Group>> {
    let merr = |message: String| FemError::Mesh {
        path: path.to_path_buf(),
        message,
    };
    let entity_phys = physical_tags_of_entities(msh);
    let mut groups: BTreeMap<(i32, i32), Group> = BTreeMap::new();
    let group_name = |dim: i32, tag: i32| {
        names
            .get(&(dim, tag))
            .cloned()
            .unwrap_or_else(|| tag.to_string())
    };
    let Some(elements) = &msh.data.elements else {
        return Err(merr("the mesh has no $Elements section".into()));
    };
    let listed: usize = elements
        .element_blocks
        .iter()
        .map(|b| b.elements.len())
        .sum();
    if usize::try_from(elements.num_elements).ok() != Some(listed) {
        return Err(merr(format!(
            "the $Elements header counts {} elements but its blocks hold {listed}",
            elements.num_elements
        )));
    }
    let mut element_tags = std::collections::HashSet::new();
    for block in &elements.element_blocks {
        let dim = block.entity_dim;
        let phys = entity_phys
            .get(&(dim, block.entity_tag))
            .cloned()
            .unwrap_or_default();
        let Some(&first) = phys.first() else {
            continue;
        };
        let kind = block_kind(block, &group_name(dim, first), path)?;
        for el in &block.elements {
            if !element_tags.insert(el.element_tag) {
                return Err(merr(format!(
                    "element tag {} is defined twice",
                    el.element_tag
                )));
            }
            let idx = el
                .nodes
                .iter()
                .map(|t| {
                    tag_to_index.get(t).copied().ok_or_else(|| {
                        merr(format!(
                            "element {} refers to unknown node {t}",
                            el.element_tag
                        ))
                    })
                })
                .collect::<Result<Vec<usize>>>()?;
            let element_index = match kind {
                Some(k) => {
                    let element =
                        volume_or_face(k, el.element_tag, idx.clone(), mesh).map_err(merr)?;
                    mesh.elements.push(element);
                    Some(mesh.elements.len() - 1)
                }
                None => None,
            };
            for &p in &phys {
                let g = groups.entry((dim, p)).or_insert_with(|| Group {
                    name: group_name(dim, p),
                    dim: usize::try_from(dim).unwrap_or(0),
                    elements: Vec::new(),
                    nodes: Vec::new(),
                });
                if let Some(e) = element_index {
                    g.elements.push(e);
                }
                g.nodes.extend_from_slice(&idx);
            }
        }
    }
    for g in groups.values_mut() {
        g.nodes.sort_unstable();
        g.nodes.dedup();
    }
    // Named groups that have no elements still exist (empty).
    for (&(dim, tag), name) in names {
        groups.entry((dim, tag)).or_insert_with(|| Group {
            name: name.clone(),
            dim: usize::try_from(dim).unwrap_or(0),
            elements: Vec::new(),
            nodes: Vec::new(),
        });
    }
    Ok(groups.into_values().collect())
}

/// The element kind a block of a physical group (`group`, named for messages) holds: `None` for
/// points and lines, and for blocks of 0D and 1D entities, which only give their nodes to their
/// groups.
///
/// # Errors
/// An element type the solver does not support, or one whose dimension is not its entity's (a
/// volume or face element in a 0D or 1D entity too).
fn block_kind(block: &ElementBlock, group: &str, path: &Path) -> Result<Option<ElementKind>> {
    let dim = block.entity_dim;
    let node_only = matches!(
        block.element_type,
        ElementType::Pnt | ElementType::Lin2 | ElementType::Lin3
    ) || dim < 2;
    match kind_of(block.element_type) {
        None if node_only => Ok(None),
        None => Err(FemError::UnsupportedElement {
            path: path.to_path_buf(),
            kind: format!("{:?}", block.element_type),
            group: group.to_string(),
        }),
        Some(k) if usize::try_from(dim).ok() != Some(k.dim()) => Err(FemError::Mesh {
            path: path.to_path_buf(),
            message: format!(
                "an element block of the {dim}D entity {} (group '{group}') holds {k:?} elements, which are {}D",
                block.entity_tag,
                k.dim()
            ),
        }),
        // (A kind's dimension is 2 or 3, so a matching entity is not node-only.)
        Some(k) => Ok((!node_only).then_some(k)),
    }
}

/// The element of kind `k` with Gmsh tag `tag` on the node indices `nodes`, checked: as many
/// nodes as the kind has, none twice (named by their tags in `mesh`).
fn volume_or_face(
    k: ElementKind,
    tag: u64,
    nodes: Vec<usize>,
    mesh: &Mesh,
) -> std::result::Result<Element, String> {
    if nodes.len() != k.num_nodes() {
        return Err(format!(
            "element {tag} has {} nodes, expected {}",
            nodes.len(),
            k.num_nodes()
        ));
    }
    let element = Element {
        kind: k,
        nodes,
        tag,
    };
    match crate::mesh::repeated_node(&element) {
        Some(a) => Err(format!(
            "element {tag} ({k:?}) names node {} twice",
            mesh.node_tags[a]
        )),
        None => Ok(element),
    }
}
