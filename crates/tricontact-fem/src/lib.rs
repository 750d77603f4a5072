//! Implicit finite-element solver for 3D solids (mesh, elements, materials, assembly, solvers, I/O).
//!
//! Work in progress: see the project issues.
