//! Equation numbering, sparsity pattern and parallel assembly.
//!
//! Global DOF `3a + i` is component `i` of node `a`; extra unknowns (e.g.
//! contact multipliers) follow at `3 n_nodes + j`. Free DOFs of active
//! nodes and all extra unknowns get equation numbers in increasing DOF
//! order; prescribed DOFs are eliminated (their residual is the reaction).
//!
//! The residual is `r = f_int(u) − f_ext + r_extra(u)`; the tangent is
//! `K = ∂r/∂u` restricted to free equations. For a prescribed-DOF increment
//! `Δu_p` the predictor right-hand side `−K_fp Δu_p` is accumulated during
//! the merge.
//!
//! Determinism: element blocks are computed in parallel (rayon) in batches,
//! then merged into the matrix in element order, so the assembled values do
//! not depend on the number of threads. The merge of the tangent runs on all
//! threads, each over all blocks but into its own range of columns (each
//! value belongs to one column): the same sums, in the same order. Where each
//! block goes is found once, with the pattern ([`Pattern`]), not at every merge.

use faer::sparse::{SparseColMat, SymbolicSparseColMat, Triplet};
use rayon::prelude::*;

use crate::analysis::Analysis;
use crate::element::{Inverted, internal_force};

/// Marker for a DOF without an equation.
pub const NO_EQ: usize = usize::MAX;

/// A result field over all mesh nodes, from [`ExtraTerms::point_fields`] (written as `.vtu`
/// point data).
#[derive(Debug, Clone, PartialEq)]
pub struct PointField {
    /// Array name.
    pub name: String,
    /// Components per node.
    pub components: usize,
    /// Values, node-major.
    pub values: Vec<f64>,
    /// The values are integers naming something (a status, a tag): written as `Int64` (see
    /// [`crate::vtu::Field::integer`]).
    pub integer: bool,
}

/// Contributions from outside the element loop (contact, springs, …), with
/// their own state.
///
/// `u` and `residual` are global DOF vectors (nodal then extra unknowns);
/// triplets `(row, col, value)` use global DOF indices and add to `∂r/∂u`.
///
/// Life cycle, driven by [`crate::driver::run`]: per increment attempt
/// [`begin_increment`](Self::begin_increment) (trial state from the committed
/// one), [`add_terms`](Self::add_terms) per Newton iteration (it may update
/// the trial state, e.g. an active set), [`after_converged`](Self::after_converged)
/// when Newton converged (`false` asks for another solve of the same increment,
/// e.g. an Uzawa update), then [`commit`](Self::commit) — or
/// [`restore`](Self::restore) on a cutback.
pub trait ExtraTerms: Send {
    /// Number of unknowns beyond the nodal DOFs.
    fn num_extra(&self) -> usize {
        0
    }
    /// The node each extra unknown belongs to (`None`: none), for the equation
    /// ordering: an unknown follows the nested-dissection block of its node, the
    /// others come last (see [`crate::ordering::equation_order`]). By default
    /// none belongs to a node.
    fn extra_nodes(&self) -> Vec<Option<usize>> {
        Vec::new()
    }
    /// For each extra unknown, whether it goes after the other extra unknowns of its node's
    /// block (an unknown that is mostly inactive, a lone diagonal, such as a node's second
    /// contact multiplier: between the others it splits the factor's supernodes; see
    /// [`crate::ordering::equation_order`]). By default none.
    fn extra_late(&self) -> Vec<bool> {
        Vec::new()
    }
    /// For each extra unknown, the factor that makes its equation's residual a force (a gap
    /// constraint: a stiffness) and, inverted, its correction a length: the weights of the
    /// convergence norms, so that they do not depend on the model's units. By default 1.
    fn residual_scales(&self) -> Vec<f64> {
        vec![1.0; self.num_extra()]
    }
    /// Whether the added tangent is symmetric (keeps Cholesky or `LDLᵀ` usable).
    fn symmetric(&self) -> bool {
        true
    }
    /// Whether the tangent stays positive definite with the added terms (`false` for the
    /// saddle-point systems of multipliers: `LDLᵀ` instead of Cholesky).
    fn definite(&self) -> bool {
        self.num_extra() == 0
    }
    /// Whether the terms are nonlinear in `u`: disables the constant-tangent
    /// shortcut of small-strain steps.
    fn nonlinear(&self) -> bool {
        self.num_extra() > 0
    }
    /// Whether the terms may support bodies (contact): skips the rigid-body
    /// support check of the bodies alone.
    fn supports_bodies(&self) -> bool {
        self.num_extra() > 0
    }
    /// Start of an increment attempt from the committed displacements `u`.
    ///
    /// # Errors
    /// A message (the attempt fails and is cut back).
    fn begin_increment(&mut self, _u: &[f64]) -> Result<(), String> {
        Ok(())
    }
    /// Adds to the residual and tangent at `u`.
    ///
    /// # Errors
    /// A message (the attempt fails and is cut back).
    fn add_terms(
        &mut self,
        u: &[f64],
        residual: &mut [f64],
        triplets: &mut Vec<(usize, usize, f64)>,
    ) -> Result<(), String>;
    /// A short note on the last [`add_terms`](Self::add_terms) for the
    /// per-iteration log (e.g. the active-set size).
    fn iteration_note(&self) -> Option<String> {
        None
    }
    /// Newton converged at `u`: `Ok(true)` accepts the increment, `Ok(false)`
    /// asks for another solve from `u` (state updated).
    ///
    /// # Errors
    /// A message (the attempt fails and is cut back).
    fn after_converged(&mut self, _u: &[f64]) -> Result<bool, String> {
        Ok(true)
    }
    /// Why the last [`after_converged`](Self::after_converged) asked for another solve (for the
    /// message when the outer loop gives up), if the terms can tell.
    fn outer_note(&self) -> Option<String> {
        None
    }
    /// After a singular tangent, before [`restore`](Self::restore): what in the last evaluated
    /// state explains it, naming nodes, if the terms can tell (`dm` says which DOFs are free).
    fn singular_cause(&self, _dm: &DofMap) -> Option<String> {
        None
    }
    /// The increment is accepted: the trial state becomes the committed one.
    fn commit(&mut self) {}
    /// The increment attempt failed: back to the committed state.
    fn restore(&mut self) {}
    /// Point fields for the result files at the committed state (values over all nodes).
    fn point_fields(&self) -> Vec<PointField> {
        Vec::new()
    }
    /// History columns at the committed state: `(name, value)`, same names
    /// every increment.
    fn history(&self) -> Vec<(String, f64)> {
        Vec::new()
    }
}

/// No extra terms.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoExtra;

impl ExtraTerms for NoExtra {
    fn add_terms(
        &mut self,
        _u: &[f64],
        _residual: &mut [f64],
        _triplets: &mut Vec<(usize, usize, f64)>,
    ) -> Result<(), String> {
        Ok(())
    }
}

/// Equation numbers of the global DOFs.
#[derive(Clone, Debug, PartialEq)]
pub struct DofMap {
    /// `eq[dof]` or [`NO_EQ`].
    pub eq: Vec<usize>,
    /// Number of equations.
    pub n_eq: usize,
    /// Number of nodal DOFs (`3 × nodes`).
    pub n_nodal: usize,
}

impl DofMap {
    /// Numbers free DOFs of active nodes, then the extra unknowns.
    ///
    /// # Panics
    /// If `prescribed` does not hold one flag per nodal DOF (`3 × active_nodes.len()`).
    #[must_use]
    pub fn new(active_nodes: &[bool], prescribed: &[bool], n_extra: usize) -> Self {
        let n_nodal = 3 * active_nodes.len();
        assert_eq!(
            prescribed.len(),
            n_nodal,
            "DofMap::new: one prescribed flag per nodal DOF (3 per node)"
        );
        let mut eq = vec![NO_EQ; n_nodal + n_extra];
        let mut n = 0;
        for (dof, e) in eq.iter_mut().enumerate() {
            let free = if dof < n_nodal {
                active_nodes[dof / 3] && !prescribed[dof]
            } else {
                true
            };
            if free {
                *e = n;
                n += 1;
            }
        }
        Self {
            eq,
            n_eq: n,
            n_nodal,
        }
    }
}

/// Sorted neighbour lists (self included) of every node through the body
/// elements.
#[must_use]
pub fn node_adjacency(an: &Analysis) -> Vec<Vec<usize>> {
    adjacency(an.mesh.nodes.len(), body_nodes(an))
}

/// The nodes of each body element, in the order of `an.body` (the order of assembly).
fn body_nodes(an: &Analysis) -> impl Iterator<Item = &[usize]> {
    an.body
        .iter()
        .map(|be| &an.mesh.elements[be.element].nodes[..])
}

/// Sorted neighbour lists (self included) of `n_nodes` nodes through `elements` (their nodes).
fn adjacency<'a>(n_nodes: usize, elements: impl Iterator<Item = &'a [usize]>) -> Vec<Vec<usize>> {
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n_nodes];
    for nodes in elements {
        for &a in nodes {
            adj[a].extend_from_slice(nodes);
        }
    }
    adj.par_iter_mut().for_each(|v| {
        v.sort_unstable();
        v.dedup();
    });
    adj
}

/// Column-compressed sparsity of the element part of the tangent, and where each body element's
/// blocks lie in it.
///
/// In every column the rows of one node are contiguous (its free DOFs, in order), and the three
/// columns of a node hold the same rows (those of its neighbours). So the block of an element's
/// nodes `a` (rows) and `b` (columns) starts at the same place in each of `b`'s columns, relative
/// to the column's start: one offset per pair of the element's nodes, found once here, places
/// all of its entries. The merge then reads them instead of searching the columns: on the fine
/// Hertz example, that search was half of the merge's time (see `scatter_parallel`).
#[derive(Clone, Debug)]
pub struct Pattern {
    /// Symbolic structure (sorted row indices).
    pub symbolic: SymbolicSparseColMat<usize>,
    /// Per body element of `n` nodes, `n × n` offsets, the pair `(a, b)` of its local nodes at
    /// `a n + b`: where node `a`'s first free row lies in each column of node `b`, from the
    /// column's start (0 where `a` or `b` has no free DOF).
    blocks: Vec<u32>,
    /// Where each body element's offsets start in `blocks` (one more than the elements).
    block_starts: Vec<usize>,
}

impl Pattern {
    /// Builds the pattern from the node adjacency of the body elements.
    #[must_use]
    pub fn new(an: &Analysis, dm: &DofMap) -> Self {
        Self::from_adjacency(&node_adjacency(an), an, dm)
    }

    /// Builds the pattern from the node adjacency of the body elements of `an` (see
    /// [`node_adjacency`]).
    ///
    /// # Panics
    /// If two nodes of a body element are not adjacent in `adj`.
    #[must_use]
    pub fn from_adjacency(adj: &[Vec<usize>], an: &Analysis, dm: &DofMap) -> Self {
        let elements: Vec<&[usize]> = body_nodes(an).collect();
        Self::from_elements(adj, &elements, dm)
    }

    /// The pattern of a node adjacency, with the block offsets of `elements` (their nodes; each
    /// pair of an element's nodes adjacent in `adj`).
    fn from_elements(adj: &[Vec<usize>], elements: &[&[usize]], dm: &DofMap) -> Self {
        let mut col_ptr = Vec::with_capacity(dm.n_eq + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for dof in 0..dm.eq.len() {
            if dm.eq[dof] == NO_EQ {
                continue;
            }
            if dof < dm.n_nodal {
                for &a in &adj[dof / 3] {
                    for i in 0..3 {
                        let r = dm.eq[3 * a + i];
                        if r != NO_EQ {
                            row_idx.push(r);
                        }
                    }
                }
            }
            col_ptr.push(row_idx.len());
        }
        let symbolic = SymbolicSparseColMat::new_checked(dm.n_eq, dm.n_eq, col_ptr, None, row_idx);
        let mut block_starts = vec![0];
        let mut total = 0;
        for nodes in elements {
            total += nodes.len().pow(2);
            block_starts.push(total);
        }
        let mut blocks = vec![0; total];
        let mut parts = Vec::with_capacity(elements.len());
        let mut rest = blocks.as_mut_slice();
        for nodes in elements {
            let (part, after) = rest.split_at_mut(nodes.len().pow(2));
            parts.push((*nodes, part));
            rest = after;
        }
        parts
            .into_par_iter()
            .for_each(|(nodes, part)| fill_blocks(&symbolic, dm, nodes, part));
        Self {
            symbolic,
            blocks,
            block_starts,
        }
    }

    /// The block offsets of body element `j` (see [`Pattern::blocks`]).
    fn blocks_of(&self, j: usize) -> &[u32] {
        &self.blocks[self.block_starts[j]..self.block_starts[j + 1]]
    }

    /// Position of `(row, col)` in the value array.
    #[inline]
    #[must_use]
    pub fn find(&self, row: usize, col: usize) -> Option<usize> {
        position(&self.symbolic, row, col)
    }
}

/// Position of `(row, col)` in the value array of `symbolic` (sorted row indices).
fn position(symbolic: &SymbolicSparseColMat<usize>, row: usize, col: usize) -> Option<usize> {
    let start = symbolic.col_ptr()[col];
    let end = symbolic.col_ptr()[col + 1];
    symbolic.row_idx()[start..end]
        .binary_search(&row)
        .ok()
        .map(|p| start + p)
}

/// The block offsets of an element with `nodes` (see [`Pattern::blocks`]) in `symbolic`, into
/// `out`.
fn fill_blocks(
    symbolic: &SymbolicSparseColMat<usize>,
    dm: &DofMap,
    nodes: &[usize],
    out: &mut [u32],
) {
    let first_free = |a: usize| (0..3).map(|i| dm.eq[3 * a + i]).find(|&e| e != NO_EQ);
    let n = nodes.len();
    for (lb, &b) in nodes.iter().enumerate() {
        let Some(col) = first_free(b) else { continue };
        let start = symbolic.col_ptr()[col];
        for (la, &a) in nodes.iter().enumerate() {
            if let Some(row) = first_free(a) {
                let at = position(symbolic, row, col).expect("an element's nodes are adjacent");
                out[la * n + lb] =
                    u32::try_from(at - start).expect("a column of fewer than 2³² entries");
            }
        }
    }
}

/// Result of one assembly.
#[derive(Clone, Debug)]
pub struct Assembled {
    /// `f_int` over all global DOFs (extra residual terms added).
    pub residual: Vec<f64>,
    /// Tangent values on the [`Pattern`] (empty if not requested).
    pub values: Vec<f64>,
    /// Extra tangent triplets in equation numbering.
    pub extra: Vec<Triplet<usize, usize, f64>>,
    /// `−K_fp Δu_p` per equation (zero without a predictor).
    pub predictor: Vec<f64>,
}

impl Assembled {
    /// Tangent as a sparse matrix (element part plus extra triplets).
    ///
    /// # Panics
    /// Only on internal inconsistency of the pattern.
    #[must_use]
    pub fn matrix(&self, pat: &Pattern) -> SparseColMat<usize, f64> {
        let base = SparseColMat::new(pat.symbolic.clone(), self.values.clone());
        if self.extra.is_empty() {
            return base;
        }
        let n = pat.symbolic.nrows();
        let extra =
            SparseColMat::try_new_from_triplets(n, n, &self.extra).expect("valid extra triplets");
        faer::sparse::ops::add(base.as_ref(), extra.as_ref()).expect("allocation")
    }
}

/// Failure of an assembly.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum AssemblyError {
    /// The body element (index into `Analysis::body`) where a point inverted.
    Inverted(usize),
    /// The extra terms failed (message).
    Extra(String),
}

const BATCH: usize = 4096;

/// Element force vector and row-major tangent block.
type Block = (Vec<f64>, Vec<f64>);

/// An element's tangent `k` (row-major, `3n × 3n`) for the merge: its `n` nodes and where its
/// blocks lie in the pattern (see [`Pattern::blocks`]).
struct Tangent<'a> {
    nodes: &'a [usize],
    blocks: &'a [u32],
    k: Vec<f64>,
}

/// Assembles internal forces, tangent (if `tangent`) and the predictor term
/// for prescribed increments `dup` (global DOF vector) if given.
///
/// # Errors
/// [`AssemblyError::Inverted`] the first (in element order) inverted
/// element; [`AssemblyError::Extra`] a failure of the extra terms.
#[allow(clippy::too_many_arguments)]
pub fn assemble(
    an: &Analysis,
    dm: &DofMap,
    pat: &Pattern,
    u: &[f64],
    nlgeom: bool,
    tangent: bool,
    dup: Option<&[f64]>,
    extra: &mut dyn ExtraTerms,
) -> Result<Assembled, AssemblyError> {
    let mut residual = vec![0.0; dm.eq.len()];
    let mut values = if tangent {
        vec![0.0; pat.symbolic.row_idx().len()]
    } else {
        Vec::new()
    };
    let mut predictor = vec![0.0; dm.n_eq];
    for (batch_index, batch) in an.body.chunks(BATCH).enumerate() {
        let blocks: Vec<Result<Block, Inverted>> = batch
            .par_iter()
            .map(|be| {
                let el = &an.mesh.elements[be.element];
                let n = el.nodes.len();
                let (x0, ue) = an.element_state(be.element, u);
                let mut f = vec![0.0; 3 * n];
                let mut k = if tangent {
                    vec![0.0; 9 * n * n]
                } else {
                    Vec::new()
                };
                internal_force(
                    an.rule(el.kind),
                    &x0,
                    &ue,
                    &an.materials[be.material],
                    nlgeom,
                    &mut f,
                    if tangent { Some(&mut k) } else { None },
                )?;
                Ok((f, k))
            })
            .collect();
        let mut tangents = Vec::with_capacity(if tangent { batch.len() } else { 0 });
        for (j, (be, block)) in batch.iter().zip(blocks).enumerate() {
            let (f, k) = block.map_err(|_| AssemblyError::Inverted(batch_index * BATCH + j))?;
            let nodes = &an.mesh.elements[be.element].nodes;
            for (la, &a) in nodes.iter().enumerate() {
                for i in 0..3 {
                    residual[3 * a + i] += f[3 * la + i];
                }
            }
            if tangent {
                tangents.push(Tangent {
                    nodes,
                    blocks: pat.blocks_of(batch_index * BATCH + j),
                    k,
                });
            }
        }
        if tangent {
            scatter_parallel(pat, dm, &tangents, dup, &mut values, &mut predictor);
        }
    }
    let mut trip = Vec::new();
    extra
        .add_terms(u, &mut residual, &mut trip)
        .map_err(AssemblyError::Extra)?;
    let mut extra_triplets = Vec::with_capacity(trip.len());
    for (r, c, v) in trip {
        let (er, ec) = (dm.eq[r], dm.eq[c]);
        if er == NO_EQ {
            continue;
        }
        if ec != NO_EQ {
            extra_triplets.push(Triplet::new(er, ec, v));
        } else if let Some(dup) = dup {
            // Prescribed column (e.g. a rigid contact tool): predictor term.
            predictor[er] -= v * dup[c];
        }
    }
    Ok(Assembled {
        residual,
        values,
        extra: extra_triplets,
        predictor,
    })
}

/// Adds the element tangents into the pattern's `values` and, for prescribed
/// columns with an increment in `dup`, `−k·Δu_p` into `predictor`: the columns in one range per
/// thread, of about as many values each (each value belongs to one column, so each range writes
/// its own part of `values`, element after element in the same order as one thread would: the
/// sums are the same bit for bit, whatever the number of threads). The merge is bound by memory
/// latency (the values it adds to), so threads overlap their waits. On the fine Hertz example
/// with a penalty (2 cores) the merge took 4.56–4.59 s of a run on one thread and 2.14–2.51 s on
/// two (three runs each, timed by a build instrumented for it), and `tricontact run` 24.9–27.5 s
/// against 26.4–31.1 s before (b24bf05, three interleaved pairs). Each block's place then came
/// from a binary search in its column, half of the merge's time; read from the pattern's block
/// offsets instead, the merge's share of the processor time in the augmented Hertz run went from
/// 13.7 % to 5.9 % (`perf`), and the assembly of the hex8 cube (`fem-bench 30`) from 0.32–0.33 s
/// to 0.24 s.
fn scatter_parallel(
    pat: &Pattern,
    dm: &DofMap,
    tangents: &[Tangent<'_>],
    dup: Option<&[f64]>,
    values: &mut [f64],
    predictor: &mut [f64],
) {
    let col_ptr = pat.symbolic.col_ptr();
    // Each range's part of the values; the predictor goes with the first.
    let (mut rest, mut predictor) = (values, Some(predictor));
    let mut work = Vec::new();
    for range in column_ranges(col_ptr, rayon::current_num_threads()) {
        let (part, tail) = rest.split_at_mut(col_ptr[range.end] - col_ptr[range.start]);
        work.push((range, part, predictor.take()));
        rest = tail;
    }
    work.into_par_iter()
        .for_each(|(range, values, mut predictor)| {
            for tangent in tangents {
                let columns = Columns {
                    range: range.clone(),
                    values: &mut *values,
                };
                scatter(pat, dm, tangent, columns, dup.zip(predictor.as_deref_mut()));
            }
        });
}

/// Cuts the columns `0..n` of a pattern with column pointers `col_ptr` (`n + 1` of them) into at
/// most `parts` consecutive ranges holding about as many values each (at least one range).
fn column_ranges(col_ptr: &[usize], parts: usize) -> Vec<std::ops::Range<usize>> {
    let n = col_ptr.len() - 1;
    let (total, parts) = (col_ptr[n], parts.max(1));
    let mut ranges = Vec::with_capacity(parts);
    let mut start = 0;
    for p in 1..parts {
        // The first column whose values start at or beyond the p-th share.
        let end = col_ptr
            .partition_point(|&v| v < total * p / parts)
            .clamp(start, n);
        if end > start {
            ranges.push(start..end);
            start = end;
        }
    }
    ranges.push(start..n);
    ranges
}

/// The equations `range` of the tangent's columns and their part of the pattern's values (from
/// the first of those columns on).
struct Columns<'a> {
    range: std::ops::Range<usize>,
    values: &'a mut [f64],
}

/// Adds the element tangent `k` into the columns `columns`, and, given the increments `dup` of
/// the prescribed DOFs, `−k·Δu_p` of every prescribed column into `predictor`.
fn scatter(
    pat: &Pattern,
    dm: &DofMap,
    &Tangent {
        nodes,
        blocks,
        ref k,
    }: &Tangent<'_>,
    columns: Columns<'_>,
    mut predictor: Option<(&[f64], &mut [f64])>,
) {
    let n = nodes.len();
    let nd = 3 * n;
    let base = pat.symbolic.col_ptr()[columns.range.start];
    for (lb, &b) in nodes.iter().enumerate() {
        for kk in 0..3 {
            let col_dof = 3 * b + kk;
            let col = dm.eq[col_dof];
            let c = 3 * lb + kk;
            if col == NO_EQ {
                // Prescribed column: predictor term only.
                if let Some((dup, predictor)) = predictor.as_mut() {
                    let d = dup[col_dof];
                    if d != 0.0 {
                        for (la, &a) in nodes.iter().enumerate() {
                            for i in 0..3 {
                                let r = dm.eq[3 * a + i];
                                if r != NO_EQ {
                                    predictor[r] -= k[(3 * la + i) * nd + c] * d;
                                }
                            }
                        }
                    }
                }
                continue;
            }
            if !columns.range.contains(&col) {
                continue;
            }
            let start = pat.symbolic.col_ptr()[col] - base;
            for (la, &a) in nodes.iter().enumerate() {
                // Rows of node `a` are contiguous in the column, from its block's offset.
                let mut p = start + blocks[la * n + lb] as usize;
                for i in 0..3 {
                    if dm.eq[3 * a + i] == NO_EQ {
                        continue;
                    }
                    columns.values[p] += k[(3 * la + i) * nd + c];
                    p += 1;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Free DOFs of active nodes are numbered in order, then the extra unknowns; a `prescribed`
    /// of the wrong length is refused by name (a short one panicked on an index, a long one was
    /// accepted).
    #[test]
    fn dofs_are_numbered_and_sizes_checked() {
        let dm = DofMap::new(
            &[true, false],
            &[false, true, false, false, false, false],
            2,
        );
        assert_eq!(dm.eq, [0, NO_EQ, 1, NO_EQ, NO_EQ, NO_EQ, 2, 3]);
        assert_eq!((dm.n_eq, dm.n_nodal), (4, 6));
        for len in [5, 7] {
            let wrong =
                std::panic::catch_unwind(|| DofMap::new(&[true, true], &vec![false; len], 0));
            let message = wrong.expect_err("a prescribed list of the wrong length");
            let text = message
                .downcast_ref::<String>()
                .cloned()
                .unwrap_or_default();
            assert!(
                text.contains("DofMap::new: one prescribed flag per nodal DOF"),
                "{len}: {text}"
            );
        }
    }

    /// The tangent scattered in ranges of columns, one per thread, equals, bit for bit, the same
    /// tangents added one entry at a time into a dense matrix in element order (at the pattern's
    /// places), and so does the predictor of the prescribed columns, on 1, 2, 3 and 7 threads:
    /// overlapping elements of four nodes on a chain of nine, some DOFs prescribed (with and
    /// without an increment), one node inactive, and one extra unknown after the nodal DOFs.
    #[test]
    fn the_column_ranges_scatter_what_one_pass_adds() {
        let elements: [&[usize]; 4] = [&[0, 1, 2, 3], &[2, 3, 4, 5], &[5, 6, 7, 8], &[1, 3, 5, 7]];
        let mut active = [true; 10];
        active[9] = false;
        let mut prescribed = [false; 30];
        for dof in [0, 1, 2, 13, 25] {
            prescribed[dof] = true;
        }
        let dm = DofMap::new(&active, &prescribed, 1);
        let pat = Pattern::from_elements(&adjacency(10, elements.into_iter()), &elements, &dm);
        let mut next = tricontact::search::scenes::uniform(7);
        let tangents: Vec<Tangent<'_>> = elements
            .iter()
            .enumerate()
            .map(|(j, &nodes)| Tangent {
                nodes,
                blocks: pat.blocks_of(j),
                k: (0..144).map(|_| next() - 0.5).collect(),
            })
            .collect();
        let mut dup = vec![0.0; 31];
        dup[1] = 0.25;
        dup[25] = -0.5;
        let n = dm.n_eq;
        let (mut dense, mut expected) = (vec![0.0; n * n], vec![0.0; n]);
        for Tangent { nodes, k, .. } in &tangents {
            let dofs: Vec<usize> = nodes.iter().flat_map(|&a| 3 * a..3 * a + 3).collect();
            for (c, &cd) in dofs.iter().enumerate() {
                for (r, &rd) in dofs.iter().enumerate() {
                    let (er, ec) = (dm.eq[rd], dm.eq[cd]);
                    if er == NO_EQ {
                        continue;
                    }
                    let v = k[r * dofs.len() + c];
                    if ec == NO_EQ {
                        if dup[cd] != 0.0 {
                            expected[er] -= v * dup[cd];
                        }
                    } else {
                        dense[er * n + ec] += v;
                    }
                }
            }
        }
        for threads in [1, 2, 3, 7] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut values = vec![0.0; pat.symbolic.row_idx().len()];
            let mut predictor = vec![0.0; dm.n_eq];
            pool.install(|| {
                scatter_parallel(
                    &pat,
                    &dm,
                    &tangents,
                    Some(&dup),
                    &mut values,
                    &mut predictor,
                );
            });
            let mut filled = 0;
            for col in 0..n {
                for (p, &row) in pat
                    .symbolic
                    .row_idx()
                    .iter()
                    .enumerate()
                    .take(pat.symbolic.col_ptr()[col + 1])
                    .skip(pat.symbolic.col_ptr()[col])
                {
                    assert_eq!(
                        values[p].to_bits(),
                        dense[row * n + col].to_bits(),
                        "({row}, {col}) on {threads} threads"
                    );
                    filled += usize::from(values[p] != 0.0);
                }
            }
            assert!(filled > 100 && n > 20, "{filled} entries of {n} equations");
            for (got, want) in predictor.iter().zip(&expected) {
                assert_eq!(got.to_bits(), want.to_bits());
            }
        }
        assert!(expected.iter().filter(|&&v| v != 0.0).count() > 5);
    }

    /// Column ranges cover every column once, in order, no more of them than asked for (and at
    /// least one), each holding at most a share of the values plus one column's.
    #[test]
    fn column_ranges_cover_the_columns_in_about_equal_shares() {
        let counts = [3usize, 0, 0, 9, 1, 4, 4, 0, 12, 2, 7, 5];
        let mut col_ptr = vec![0];
        for c in counts {
            col_ptr.push(col_ptr.last().unwrap() + c);
        }
        let total = *col_ptr.last().unwrap();
        for parts in [0, 1, 2, 3, 5, 12, 40] {
            let ranges = column_ranges(&col_ptr, parts);
            assert!(
                !ranges.is_empty() && ranges.len() <= parts.max(1),
                "{parts}: {ranges:?}"
            );
            assert_eq!(ranges[0].start, 0);
            assert_eq!(ranges.last().unwrap().end, counts.len());
            for pair in ranges.windows(2) {
                assert_eq!(pair[0].end, pair[1].start, "{parts}: {ranges:?}");
            }
            for r in &ranges {
                let held = col_ptr[r.end] - col_ptr[r.start];
                assert!(
                    held <= total / parts.max(1) + 12,
                    "{parts}: {r:?} holds {held} of {total}"
                );
            }
        }
        assert_eq!(column_ranges(&[0], 4), vec![0..0]);
        assert_eq!(column_ranges(&[0, 0, 0], 2), vec![0..2]);
    }
}
