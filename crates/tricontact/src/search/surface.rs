//! A master surface for the search: facets as node-index triples, and their adjacency.
//!
//! Node positions are not stored: every search call takes the current positions, so the same
//! surface serves every increment. Facet adjacency (facets sharing at least one node, the facet
//! itself excluded, sorted by index) is built once, in compressed-row form, for callers that walk
//! the surface.

use thiserror::Error;

/// Most facets a surface may have: a tree leaf names its first slot in 27 bits
/// (`search::node`), and adjacency rows, about 12 entries per facet on a regular mesh, keep their
/// offsets in `u32` with room to spare.
pub const MAX_FACETS: usize = (1 << 27) - 1;

/// Why a surface could not be built or searched.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SurfaceError {
    /// A facet names a node that does not exist.
    #[error("facet {facet} refers to node {node}, but only {nodes} node positions were given")]
    NodeOutOfRange {
        /// The facet index.
        facet: usize,
        /// The node index it names.
        node: u32,
        /// How many node positions there are.
        nodes: usize,
    },
    /// Fewer node positions were given than the surface has nodes.
    #[error("the surface has {expected} nodes but {given} positions were given")]
    PositionCount {
        /// Nodes of the surface.
        expected: usize,
        /// Positions given.
        given: usize,
    },
    /// The surface has more facets than the search indexes ([`MAX_FACETS`]).
    #[error(
        "{facets} facets exceed the search's limit of {} facets per surface",
        MAX_FACETS
    )]
    TooLarge {
        /// The number of facets given.
        facets: usize,
    },
    /// An incremental search was given another number of queries than its lists were made for.
    #[error("the neighbourhood lists were made for {expected} queries but {given} were given")]
    QueryCount {
        /// Queries the lists were made for.
        expected: usize,
        /// Queries given.
        given: usize,
    },
    /// An incremental search was given another surface than its lists were made on.
    #[error(
        "the neighbourhood lists were made on a surface of {expected_facets} facets over {expected_nodes} nodes, but this one has {facets} facets over {nodes} nodes"
    )]
    OtherSurface {
        /// Facets of the surface the lists were made on.
        expected_facets: usize,
        /// Its nodes.
        expected_nodes: usize,
        /// Facets of the surface given.
        facets: usize,
        /// Its nodes.
        nodes: usize,
    },
    /// An answer buffer does not have one entry per query.
    #[error("the answer buffer holds {answers} entries for {queries} queries")]
    AnswerCount {
        /// Queries given.
        queries: usize,
        /// Entries in the answer buffer.
        answers: usize,
    },
    /// Neighbourhood lists longer than the search's 32-bit offsets.
    #[error("the neighbourhood lists hold {entries} entries, more than 2³² (use a smaller skin)")]
    ListsTooLong {
        /// The number of listed facets.
        entries: usize,
    },
    /// A length parameter of the search (the boxes' inflation, the lists' skin) that is negative
    /// or NaN (or, for the skin, infinite).
    #[error("the {name} must be a length ≥ 0 (got {value})")]
    BadLength {
        /// Which parameter.
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// More nodes than the facets' 32-bit node indices can name.
    #[error("{nodes} nodes exceed the 2³² that the facets' 32-bit node indices can name")]
    TooManyNodes {
        /// The node count given.
        nodes: usize,
    },
    /// A facet names the same node twice.
    #[error("facet {facet} repeats node {node}")]
    RepeatedNode {
        /// The facet index.
        facet: usize,
        /// The repeated node.
        node: u32,
    },
}

/// Facets (node-index triples) with their node-sharing adjacency.
#[derive(Debug, Clone)]
pub struct Surface {
    facets: Vec<[u32; 3]>,
    node_count: usize,
    adjacency_start: Vec<u32>,
    adjacency: Vec<u32>,
}

impl Surface {
    /// Builds the surface of `facets` over `node_count` nodes.
    ///
    /// # Errors
    /// [`SurfaceError`] for a node index out of range or repeated within a facet.
    pub fn new(facets: Vec<[u32; 3]>, node_count: usize) -> Result<Self, SurfaceError> {
        if facets.len() > MAX_FACETS {
            return Err(SurfaceError::TooLarge {
                facets: facets.len(),
            });
        }
        // The adjacency has an entry per node: a count no index can reach would only exhaust
        // memory (or overflow).
        if u64::try_from(node_count).is_ok_and(|n| n > 1 << 32) {
            return Err(SurfaceError::TooManyNodes { nodes: node_count });
        }
        for (f, nodes) in facets.iter().enumerate() {
            for (k, &n) in nodes.iter().enumerate() {
                if n as usize >= node_count {
                    return Err(SurfaceError::NodeOutOfRange {
                        facet: f,
                        node: n,
                        nodes: node_count,
                    });
                }
                if nodes[..k].contains(&n) {
                    return Err(SurfaceError::RepeatedNode { facet: f, node: n });
                }
            }
        }
        let (adjacency_start, adjacency) = adjacency(&facets, node_count);
        Ok(Self {
            facets,
            node_count,
            adjacency_start,
            adjacency,
        })
    }

    /// The facets' node triples.
    #[must_use]
    #[inline]
    pub fn facets(&self) -> &[[u32; 3]] {
        &self.facets
    }

    /// The number of facets.
    #[must_use]
    #[inline]
    pub fn len(&self) -> usize {
        self.facets.len()
    }

    /// `true` for a surface without facets.
    #[must_use]
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.facets.is_empty()
    }

    /// The number of nodes the facets index into.
    #[must_use]
    #[inline]
    pub fn node_count(&self) -> usize {
        self.node_count
    }

    /// Checks that `positions` covers every node of the surface.
    ///
    /// # Errors
    /// [`SurfaceError::PositionCount`] when it does not.
    pub fn check_positions(&self, positions: &[crate::Vec3]) -> Result<(), SurfaceError> {
        if positions.len() < self.node_count {
            return Err(SurfaceError::PositionCount {
                expected: self.node_count,
                given: positions.len(),
            });
        }
        Ok(())
    }

    /// The three node positions of `facet`.
    #[must_use]
    #[inline]
    pub fn corners(&self, facet: u32, positions: &[crate::Vec3]) -> [crate::Vec3; 3] {
        let [a, b, c] = self.facets[facet as usize];
        [
            positions[a as usize],
            positions[b as usize],
            positions[c as usize],
        ]
    }

    /// Facets sharing at least one node with `facet`, in increasing order.
    #[must_use]
    #[inline]
    pub fn neighbours(&self, facet: u32) -> &[u32] {
        let f = facet as usize;
        &self.adjacency[self.adjacency_start[f] as usize..self.adjacency_start[f + 1] as usize]
    }
}

/// Compressed rows of `node → facets`, then of `facet → facets sharing a node`.
fn adjacency(facets: &[[u32; 3]], node_count: usize) -> (Vec<u32>, Vec<u32>) {
    let mut node_start = vec![0u32; node_count + 1];
    for f in facets {
        for &n in f {
            node_start[n as usize + 1] += 1;
        }
    }
    for n in 0..node_count {
        node_start[n + 1] += node_start[n];
    }
    let mut fill = node_start.clone();
    let mut node_facets = vec![0u32; node_start[node_count] as usize];
    for (i, f) in facets.iter().enumerate() {
        for &n in f {
            node_facets[fill[n as usize] as usize] = to_u32(i);
            fill[n as usize] += 1;
        }
    }
    let mut start = Vec::with_capacity(facets.len() + 1);
    let mut adjacent = Vec::with_capacity(facets.len() * 12);
    let mut row = Vec::with_capacity(32);
    start.push(0);
    for (i, f) in facets.iter().enumerate() {
        row.clear();
        for &n in f {
            let range = node_start[n as usize] as usize..node_start[n as usize + 1] as usize;
            row.extend(
                node_facets[range]
                    .iter()
                    .copied()
                    .filter(|&g| g as usize != i),
            );
        }
        row.sort_unstable();
        row.dedup();
        adjacent.extend_from_slice(&row);
        start.push(to_u32(adjacent.len()));
    }
    (start, adjacent)
}

/// Indices are stored as `u32`; [`Surface::new`] rejects surfaces whose indices would not fit.
#[inline]
fn to_u32(i: usize) -> u32 {
    debug_assert!(u32::try_from(i).is_ok());
    #[allow(clippy::cast_possible_truncation)]
    let v = i as u32;
    v
}
