//! Line 3 of Algorithm 1, the neighbor search: the counting sort of the particles by cell,
//! written once over the sort passes each backend supplies (`coil_kernels::counting_sort`,
//! `cell_grid`, `fluid_cells`). Particles outside the domain fall into the last bucket and
//! drop out.

use coil_kernels::counting_sort::{scan_by_levels, ScanStep};

/// A backend's sort passes over its own buffers, each run over all particles, buckets or scan
/// chunks at once.
pub trait SortPasses {
    type Fault;
    /// Scan chunks of the buckets (the backend's chunk length, `counting_sort`).
    fn chunks(&self) -> usize;
    /// Each live particle's cell key (`hash_pass`).
    fn hash(&mut self) -> Result<(), Self::Fault>;
    /// Every bucket's counter to zero.
    fn clear_counters(&mut self) -> Result<(), Self::Fault>;
    /// Each bucket's particles counted (`count_particle`).
    fn count_particles(&mut self) -> Result<(), Self::Fault>;
    /// Each scan chunk's total, the first level of the scan (`chunk_total`).
    fn chunk_totals(&mut self) -> Result<(), Self::Fault>;
    /// One step of the scan of the chunk totals (`scan_by_levels`).
    fn scan_step(&mut self, step: ScanStep) -> Result<(), Self::Fault>;
    /// Each chunk's buckets scanned from its offset: every cell's start (`scan_chunk`).
    fn scan_chunks(&mut self) -> Result<(), Self::Fault>;
    /// Each particle's place in its bucket (`scatter`), then each cell's places in the order the
    /// particles had (`sort_bucket`), so that the sort is stable.
    fn scatter_and_sort_buckets(&mut self) -> Result<(), Self::Fault>;
    /// The live count, from the buckets, and every carried array gathered into the sorted
    /// order (`carried_state`).
    fn reorder(&mut self) -> Result<(), Self::Fault>;
    /// The cells near fluid (`fluid_cells`), where the grid tracks fluid.
    fn mark_cells_near_fluid(&mut self) -> Result<(), Self::Fault>;
}

/// Sorts the particles by cell with `passes`.
pub fn sort_by_cell<P: SortPasses>(passes: &mut P) -> Result<(), P::Fault> {
    passes.hash()?;
    passes.clear_counters()?;
    passes.count_particles()?;
    passes.chunk_totals()?;
    scan_by_levels(passes.chunks(), |step| passes.scan_step(step))?;
    passes.scan_chunks()?;
    passes.scatter_and_sort_buckets()?;
    passes.reorder()?;
    passes.mark_cells_near_fluid()
}
