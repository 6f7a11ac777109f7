//! Adaptive remeshing in material space: the geometry half of Oliveira 2013 §4.5 (spec §6) and of the
//! methods it is compared with. Everything here works on the 2-D rest (material) coordinates X of the
//! cloth, as the thesis does (spec §6.6: "generation happens in the planar rest space … so every new
//! spring has a well-defined rest length"); world positions x and velocities v are only carried along,
//! by barycentric interpolation (spec §6.7).
//!
//! * [`AdaptiveMesh`] — the editable mesh (spec §6.1, A-1): per-vertex X, x, v; per-face vertex
//!   triples; half-edge twins kept valid by every edit; a [`ChangeLog`] saying which vertices are new
//!   (with parents and barycentric weights) and which faces went and came, so that the cloth refreshes
//!   masses, springs and bending elements locally (spec §6.7, A-41). Per-vertex areas (one third of
//!   the incident rest areas) sum to a total rest area every operation conserves.
//! * Operators (spec §6.1, §6.5, A-35, A-36, A-39, A-40): [`AdaptiveMesh::split_edge`],
//!   [`AdaptiveMesh::flip_edge`], [`AdaptiveMesh::collapse_edge`], [`AdaptiveMesh::replace_patch`],
//!   [`AdaptiveMesh::region_border`] and [`AdaptiveMesh::remesh_region`] (delete a face set and
//!   fill the hole with the local mesh generator).
//! * [`local_mesh`] — the planar hole mesher of spec §6.6: quadtree sizing from the
//!   border, advancing front, Laplacian smoothing and bad-triangle removal, with the retry loop.
//! * [`subdivision`] — the Simnett et al. 2009 1-to-4 edge-subdivision baseline of Test III (spec §2.3,
//!   §7.3, A-42).
//! * [`sizing`] — remeshing by a sizing metric in the manner of Narain, Samii & O'Brien 2012 (ARCSim,
//!   spec §2.4): split, flip and collapse driven by per-face 2 × 2 metrics built from curvature,
//!   velocity gradient and compression. Not the thesis's method; anima offers it as the modern
//!   reference point the spec names.
//!
//! What this module is not: it evaluates no adaptivity *criteria* that need physics (collisions,
//! time stamps, thresholds of Tables 5.1–5.5); the cloth crate decides which edges to refine and calls
//! these operators.

mod crossing_guard;
pub mod local_mesh;
mod mesh;
mod ops;
mod region;
pub mod sizing;
pub mod subdivision;

pub use mesh::{AdaptiveMesh, AdaptiveMeshError, ChangeLog, NONE, NewVertex, OpCounts, OpError, Renumbering};
pub use ops::{OpGuards, loop_points};
pub use region::{ContourRule, RegionError, RegionRemeshing, RegionReport, border_density};
pub use subdivision::{Subdivision, SubdivisionError};

#[cfg(test)]
mod tests;
