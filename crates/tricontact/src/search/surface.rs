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
    /// A search tree or neighbourhood lists were given another surface than the one they were made
    /// on (other facet or node counts, or the same counts and other facets).
    #[error(
        "the {made} was made on another surface (that one: {expected_facets} facets over {expected_nodes} nodes; this one: {facets} facets over {nodes} nodes)"
    )]
    OtherSurface {
        /// What was made on the other surface: "search tree" or "set of neighbourhood lists".
        made: &'static str,
        /// Facets of the surface it was made on.
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

/// What a search tree or neighbourhood lists keep of the surface they were made on: its facet
/// and node counts and a 64-bit hash of its facets' node indices, in order. They index the
/// surface's facets and nodes by number, so another surface, even one with the same counts (the
/// surface of a second body), is refused rather than searched; a copy of the same surface (equal
/// facets over as many nodes) is the same surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct SurfaceKey {
    facets: usize,
    nodes: usize,
    hash: u64,
}

impl SurfaceKey {
    /// `Ok` when `surface` is the one this key was taken from.
    ///
    /// # Errors
    /// [`SurfaceError::OtherSurface`], naming `made` (what was made on the key's surface), when it
    /// is not.
    pub(crate) fn check(self, surface: &Surface, made: &'static str) -> Result<(), SurfaceError> {
        if surface.key == self {
            return Ok(());
        }
        Err(SurfaceError::OtherSurface {
            made,
            expected_facets: self.facets,
            expected_nodes: self.nodes,
            facets: surface.len(),
            nodes: surface.node_count(),
        })
    }

    /// As [`SurfaceKey::check`], for the calls that return no `Result`.
    ///
    /// # Panics
    /// With the error's message when `surface` is not the key's.
    #[track_caller]
    pub(crate) fn expect(self, surface: &Surface, made: &'static str) {
        if let Err(e) = self.check(surface, made) {
            panic!("{e}");
        }
    }
}

/// The facets' hash: the wrapping sum over facets `f` of `mix(a | b << 32) ^ mix(c | f << 32)`
/// for nodes `[a, b, c]`, with `mix` the 64-bit finalizer of MurmurHash3. Each facet's term is
/// independent of the others (no chain of dependent multiplies through 10⁶ facets), and the
/// facet's index in it makes the sum depend on the facets' order.
fn facets_hash(facets: &[[u32; 3]]) -> u64 {
    fn mix(mut z: u64) -> u64 {
        z = (z ^ (z >> 33)).wrapping_mul(0xff51_afd7_ed55_8ccd);
        z = (z ^ (z >> 33)).wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        z ^ (z >> 33)
    }
    (0u64..)
        .zip(facets)
        .map(|(f, &[a, b, c])| mix(u64::from(a) | u64::from(b) << 32) ^ mix(u64::from(c) | f << 32))
        .fold(0, u64::wrapping_add)
}

/// Facets (node-index triples) with their node-sharing adjacency.
#[derive(Debug, Clone)]
pub struct Surface {
    facets: Vec<[u32; 3]>,
    node_count: usize,
    adjacency_start: Vec<u32>,
    adjacency: Vec<u32>,
    key: SurfaceKey,
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
        let key = SurfaceKey {
            facets: facets.len(),
            nodes: node_count,
            hash: facets_hash(&facets),
        };
        Ok(Self {
            facets,
            node_count,
            adjacency_start,
            adjacency,
            key,
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

    /// What a tree or lists made on this surface keep of it (see [`SurfaceKey`]).
    #[inline]
    pub(crate) fn key(&self) -> SurfaceKey {
        self.key
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
    ///
    /// # Panics
    /// If `facet` is not below [`Surface::len`], or `positions` holds no position for one of its
    /// nodes.
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
    ///
    /// # Panics
    /// If `facet` is not below [`Surface::len`].
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
