//! Node-to-triangular-facet contact kernel.
