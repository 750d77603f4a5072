//! In-memory mesh: node coordinates, elements and named physical groups.
//!
//! Node and element indices are 0-based positions in the vectors below; the
//! original Gmsh tags are kept for messages. Element node order follows Gmsh
//! (which equals VTK for tet4 and hex8; tet10 differs from VTK in nodes 8/9,
//! see [`crate::vtu`]).
//!
//! A physical group of dimension 3 is an *element set*, of dimension 2 a
//! *surface* (its triangle/quad faces), and every group is a *node set*.

use crate::error::FemError;

/// Supported element types.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ElementKind {
    /// 4-node linear tetrahedron.
    Tet4,
    /// 10-node quadratic tetrahedron.
    Tet10,
    /// 8-node trilinear hexahedron.
    Hex8,
    /// 3-node triangle face.
    Tri3,
    /// 6-node quadratic triangle face.
    Tri6,
    /// 4-node bilinear quadrilateral face.
    Quad4,
}

impl ElementKind {
    /// Number of nodes.
    #[must_use]
    pub fn num_nodes(self) -> usize {
        match self {
            Self::Tet4 => 4,
            Self::Tet10 => 10,
            Self::Hex8 => 8,
            Self::Tri3 => 3,
            Self::Tri6 => 6,
            Self::Quad4 => 4,
        }
    }

    /// Topological dimension (3 for volumes, 2 for faces).
    #[must_use]
    pub fn dim(self) -> usize {
        match self {
            Self::Tet4 | Self::Tet10 | Self::Hex8 => 3,
            Self::Tri3 | Self::Tri6 | Self::Quad4 => 2,
        }
    }

    /// Number of corner (vertex) nodes, which come first in the node list.
    #[must_use]
    pub fn num_corners(self) -> usize {
        match self {
            Self::Tet4 | Self::Tet10 => 4,
            Self::Hex8 => 8,
            Self::Tri3 | Self::Tri6 => 3,
            Self::Quad4 => 4,
        }
    }

    /// Short name used in summaries.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Tet4 => "tet4",
            Self::Tet10 => "tet10",
            Self::Hex8 => "hex8",
            Self::Tri3 => "tri3",
            Self::Tri6 => "tri6",
            Self::Quad4 => "quad4",
        }
    }
}

/// One volume or face element.
#[derive(Clone, Debug, PartialEq)]
pub struct Element {
    /// Element type.
    pub kind: ElementKind,
    /// Node indices (0-based), Gmsh order.
    pub nodes: Vec<usize>,
    /// Gmsh element tag (for messages).
    pub tag: u64,
}

/// A named physical group.
#[derive(Clone, Debug, PartialEq)]
pub struct Group {
    /// Physical name (or the tag number as text when unnamed).
    pub name: String,
    /// Dimension of the group (0..=3).
    pub dim: usize,
    /// Elements (indices into [`Mesh::elements`]) for dimension 2 and 3.
    pub elements: Vec<usize>,
    /// Sorted, unique node indices of every entity in the group.
    pub nodes: Vec<usize>,
}

impl Group {
    /// The group's nodes `a` with `keep[a]` (e.g. the nodes of bodies), in order.
    #[must_use]
    pub fn nodes_in(&self, keep: &[bool]) -> Vec<usize> {
        self.nodes.iter().copied().filter(|&a| keep[a]).collect()
    }
}

/// A mesh with its physical groups.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Node coordinates.
    pub nodes: Vec<[f64; 3]>,
    /// Gmsh node tags, parallel to `nodes`.
    pub node_tags: Vec<u64>,
    /// Volume and face elements that belong to physical groups.
    pub elements: Vec<Element>,
    /// Physical groups.
    pub groups: Vec<Group>,
}

/// A node that a volume element names twice (its index), `None` for faces and for a valid
/// element. Such an element has lost a corner: a hexahedron collapsed that way can keep positive
/// Jacobians and splits the mesh without a word.
#[must_use]
pub fn repeated_node(e: &Element) -> Option<usize> {
    if e.kind.dim() != 3 {
        return None;
    }
    let nodes = &e.nodes;
    (1..nodes.len()).find_map(|i| nodes[..i].contains(&nodes[i]).then_some(nodes[i]))
}

impl Mesh {
    /// Checks what the Gmsh reader guarantees, for a mesh built by other code: every coordinate
    /// finite and within ±[`crate::gmsh::MAX_COORDINATE`] ([`crate::gmsh::coordinate_fault`]), a
    /// tag per node, every element with the
    /// node count of its kind and its nodes in range, every group's nodes and elements in range.
    ///
    /// # Errors
    /// [`FemError::Invalid`] naming the first node, element or group at fault.
    pub fn check(&self) -> Result<(), FemError> {
        let invalid = |s: String| Err(FemError::Invalid(vec![format!("mesh: {s}")]));
        if self.node_tags.len() != self.nodes.len() {
            return invalid(format!(
                "{} node tags for {} nodes",
                self.node_tags.len(),
                self.nodes.len()
            ));
        }
        for (x, tag) in self.nodes.iter().zip(&self.node_tags) {
            if let Some(fault) = crate::gmsh::coordinate_fault(x) {
                return invalid(format!("node {tag} has {fault}"));
            }
        }
        let n = self.nodes.len();
        for e in &self.elements {
            if e.nodes.len() != e.kind.num_nodes() {
                return invalid(format!(
                    "element {} ({:?}) has {} nodes, not {}",
                    e.tag,
                    e.kind,
                    e.nodes.len(),
                    e.kind.num_nodes()
                ));
            }
            if let Some(&a) = e.nodes.iter().find(|&&a| a >= n) {
                return invalid(format!("element {} names node index {a} of {n}", e.tag));
            }
            if let Some(a) = repeated_node(e) {
                return invalid(format!(
                    "element {} ({:?}) names node {} twice",
                    e.tag, e.kind, self.node_tags[a]
                ));
            }
        }
        for g in &self.groups {
            if let Some(&a) = g.nodes.iter().find(|&&a| a >= n) {
                return invalid(format!("group '{}' names node index {a} of {n}", g.name));
            }
            let m = self.elements.len();
            if let Some(&e) = g.elements.iter().find(|&&e| e >= m) {
                return invalid(format!("group '{}' names element index {e} of {m}", g.name));
            }
        }
        Ok(())
    }

    /// Finds a group by name (the one of lowest dimension if the name is used in several; the
    /// model's references go through [`Mesh::lookup`], which reports that case).
    #[must_use]
    pub fn group(&self, name: &str) -> Option<&Group> {
        self.groups.iter().find(|g| g.name == name)
    }

    /// The group a model names, `Ok(None)` if there is none. Gmsh allows one name (or one
    /// number, for unnamed groups) in several dimensions: then the group of dimension `dim` is
    /// taken when the reference needs one (a body: 3, a contact or pressure surface: 2), and
    /// otherwise the reference is ambiguous — an error naming the dimensions, since their node
    /// sets differ.
    ///
    /// # Errors
    /// The message when `name` is ambiguous.
    pub fn lookup(&self, name: &str, dim: Option<usize>) -> Result<Option<&Group>, String> {
        let found: Vec<&Group> = self.groups.iter().filter(|g| g.name == name).collect();
        if found.len() <= 1 {
            return Ok(found.first().copied());
        }
        if let Some(g) = dim.and_then(|d| found.iter().find(|g| g.dim == d)) {
            return Ok(Some(g));
        }
        let dims: Vec<String> = found.iter().map(|g| format!("{}D", g.dim)).collect();
        Err(format!(
            "group '{name}' is ambiguous: the mesh has physical groups of that name in {}; \
             give them different names in the .geo file",
            dims.join(" and ")
        ))
    }

    /// Comma-separated description of the groups, e.g. `beam (3D), tip (2D)`.
    #[must_use]
    pub fn group_list(&self) -> String {
        if self.groups.is_empty() {
            return "none".to_string();
        }
        self.groups
            .iter()
            .map(|g| format!("{} ({}D)", g.name, g.dim))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The smallest and largest coordinates of the nodes (`+∞` and `−∞` without nodes).
    #[must_use]
    pub fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.nodes {
            for i in 0..3 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
        (lo, hi)
    }

    /// Characteristic length: the diagonal of the bounding box.
    #[must_use]
    pub fn size(&self) -> f64 {
        if self.nodes.is_empty() {
            return 0.0;
        }
        let (lo, hi) = self.bounding_box();
        ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt()
    }

    /// Counts elements per kind, in kind order.
    #[must_use]
    pub fn count_kinds(&self) -> Vec<(ElementKind, usize)> {
        let mut counts = std::collections::BTreeMap::new();
        for e in &self.elements {
            *counts.entry(e.kind).or_insert(0usize) += 1;
        }
        counts.into_iter().collect()
    }
}
