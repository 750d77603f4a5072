//! The lists brought to new node positions: each surface node's motion `mₙ = xₙ − x₀ₙ` since the
//! lists were made, and the longest, `δ = maxₙ |mₙ|`, in one pass over the nodes; and the facets
//! that were degenerate when the lists were made and are valid now.
//!
//! This is the incremental search's counterpart of a tree's refit: it depends on the positions
//! only, not on the queries, and [`Moved::closest_all_into`] reads it for as many sets of answers
//! at these positions as the caller asks for. [`Neighbourhoods::closest_all_into`] makes one and
//! answers once.
//!
//! The motions go into a buffer the calling thread keeps from one `Moved` to the next: a fresh one
//! (12 MB at 10⁶ facets) was mapped and zeroed by the system each time.

use rayon::prelude::*;

use super::answer::is_degenerate;
use super::{LISTS, Neighbourhoods, longer};
use crate::linalg::Vec3;
use crate::search::surface::{Surface, SurfaceError};

/// [`Neighbourhoods`] at node positions other than those they were made at: the node motions and
/// the longest, ready for [`Moved::closest_all_into`] (see the module documentation).
pub struct Moved<'a> {
    pub(super) lists: &'a Neighbourhoods,
    pub(super) surface: &'a Surface,
    pub(super) positions: &'a [Vec3],
    /// `x − x₀` per surface node.
    pub(super) moves: Vec<Vec3>,
    /// The longest motion `δ` (NaN if a position is NaN).
    pub(super) delta: f64,
    /// The facets degenerate when the lists were made and valid at `positions`.
    pub(super) valid: Vec<u32>,
}

impl Neighbourhoods {
    /// The lists at node `positions` of `surface` (the surface they were made on): each node's
    /// motion since then and the longest, computed once for any number of
    /// [`Moved::closest_all_into`] at these positions.
    ///
    /// # Errors
    /// [`SurfaceError::PositionCount`] if `positions` misses nodes of the surface;
    /// [`SurfaceError::OtherSurface`] if `surface` is not the one the lists were made on.
    pub fn moved<'a>(
        &'a self,
        surface: &'a Surface,
        positions: &'a [Vec3],
    ) -> Result<Moved<'a>, SurfaceError> {
        surface.check_positions(positions)?;
        self.surface.check(surface, LISTS)?;
        let valid = self
            .degenerate
            .iter()
            .copied()
            .filter(|&f| !is_degenerate(&surface.corners(f, positions)))
            .collect();
        let mut moves = MOVES.take();
        let delta = self.moves_into(positions, &mut moves);
        // The unchecked reads of `Moved::closest_all_into` rely on one motion per node.
        debug_assert_eq!(moves.len(), surface.node_count());
        Ok(Moved {
            lists: self,
            surface,
            positions,
            moves,
            delta,
            valid,
        })
    }

    /// Writes each surface node's motion `x − x₀` since the lists were made into `moves` (resized
    /// to the nodes) and returns the longest (NaN if one is NaN), in one pass.
    pub(super) fn moves_into(&self, positions: &[Vec3], moves: &mut Vec<Vec3>) -> f64 {
        const RUN: usize = 4096;
        moves.resize(self.reference.len(), Vec3::zeros());
        moves
            .par_chunks_mut(RUN)
            .zip(self.reference.par_chunks(RUN))
            .zip(positions.par_chunks(RUN))
            .map(|((m, x0), x)| {
                let mut big = 0.0;
                for ((m, x0), x) in m.iter_mut().zip(x0).zip(x) {
                    *m = x - x0;
                    big = longer(big, m.norm_squared());
                }
                big
            })
            .reduce(|| 0.0, longer)
            .sqrt()
    }
}

impl Moved<'_> {
    /// The longest node motion since the lists were made, `δ` (NaN if a position is NaN).
    #[must_use]
    pub fn motion(&self) -> f64 {
        self.delta
    }
}

impl std::fmt::Debug for Moved<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Moved")
            .field("nodes", &self.moves.len())
            .field("motion", &self.delta)
            .field("valid", &self.valid)
            .finish_non_exhaustive()
    }
}

impl Drop for Moved<'_> {
    /// Gives the motions' buffer back to the thread, for the next [`Neighbourhoods::moved`].
    fn drop(&mut self) {
        let moves = std::mem::take(&mut self.moves);
        // While the thread's locals are being destroyed the buffer is simply freed.
        let _ = MOVES.try_with(|slot| slot.set(moves));
    }
}

thread_local! {
    /// The motions' buffer of the last [`Moved`] dropped on this thread: 24 bytes per surface
    /// node, held until the thread ends. [`Neighbourhoods::moved`] takes it out, so a `Moved` made
    /// while another is alive on the same thread finds it empty and uses one of its own.
    static MOVES: std::cell::Cell<Vec<Vec3>> = const { std::cell::Cell::new(Vec::new()) };
}
