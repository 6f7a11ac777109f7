//! The adaptivity criteria of Oliveira 2013 §4.5.1 (spec §6.2–§6.4): which springs to refine and which to
//! simplify, the smoothing of both lists, and their face-connected components.
//!
//! Per edge, in the thesis's order (spec §3.2), an edge picked by one criterion is not tested by the next:
//!
//! 1. **compression** (A-26): |x_a − x_b| / L⁰ < c → refine;
//! 2. **collision** (A-27): the segment x_a → x_b meets an object and the cloth is not parallel to the
//!    surface there, |n̂_cloth · n̂_obj| < cos θ_guard (the spec's reconstruction of the unstated angle,
//!    Q-6) → refine;
//! 3. **curvature** (A-28, A-29): with unit vertex normals n̂_a, n̂_b (sum of unit face normals, Q-8),
//!    n̂_a · n̂_b < cos θ_refine · min(1, Ā/A⁰_max) → refine, n̂_a · n̂_b > cos θ_simplify → simplify.
//!
//! Guards: L⁰ < L⁰_min is never refined; L⁰ > L⁰_max is never simplified, nor is an edge
//! made by a refinement less than t_simp ago. Smoothing then adds, in one pass, the
//! neighbours (other edges of the adjacent faces) of refine edges with L⁰_i/L⁰_j < c₂, and the neighbours
//! of simplify edges that are at least 0.1·t_simp old. Components group edges sharing a face;
//! simplify edges sharing a face with a refine edge are dropped (refinement has priority, Q-15).

use std::collections::BTreeMap;

use anima_geom::remesh::AdaptiveMesh;
use anima_geom::{DVec2, DVec3};

use super::contact::{Collider, first_hit, vertex_normals};

/// How the curvature refine limit depends on the faces' size (spec §6.2.3, Q-10).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CurvatureLimit {
    /// cos θ^eff = cos θ_refine · min(1, Ā/A⁰_max): the spec's reconstruction. The default.
    #[default]
    Clamped,
    /// cos θ^eff = cos θ_refine · Ā/A⁰_max, unclamped: faces larger than A⁰_max are refined when
    /// flat.
    Literal,
}

/// The too-short-edge rule of the refinement retry loop (spec §6.6, Q-9).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum ShortEdgeRule {
    /// Reject a patch with an edge shorter than (L⁰_min)², the number as printed (metres squared read as
    /// metres). The default: it is what lets the thesis's remeshing make edges shorter than 1-to-4's.
    #[default]
    LiteralSquare,
    /// Reject a patch with an edge shorter than L⁰_min.
    MinLength,
}

/// Every parameter of the thesis's remesher (Tables 5.1, 5.3, 5.5) and every switch the spec marks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OliveiraRemeshing {
    /// c: refine when current/rest length falls below this (70 %).
    pub compression: f64,
    /// cos θ_refine of the curvature criterion (0.97).
    pub cos_refine: f64,
    /// cos θ_simplify (0.999995).
    pub cos_simplify: f64,
    /// cos θ_guard of the collision criterion's angle test (Q-6; the spec's 0.97).
    pub cos_collision_guard: f64,
    /// L⁰_min, m.
    pub min_rest_length: f64,
    /// L⁰_max, m.
    pub max_rest_length: f64,
    /// t_simp, s.
    pub time_to_simplify: f64,
    /// c₂ of Eq. 4.19.
    pub smoothing_ratio: f64,
    /// Density percentage for refinement (101 %).
    pub density_refine: f64,
    /// Density percentage for simplification.
    pub density_simplify: f64,
    pub curvature_limit: CurvatureLimit,
    pub short_edge: ShortEdgeRule,
    /// Cap on the retry loop (the spec's 50).
    pub max_tries: usize,
    /// Smoothing and flip rounds of the local mesher.
    pub improvement_rounds: usize,
    /// Run the simplification criteria at all (on by default).
    pub simplify: bool,
    /// After a simplification is refused (its patch has no fewer faces, or none meets the edge-length
    /// rules), its region's edges are stamped as if just refined, so they wait t_simp before they are
    /// selected again (anima's; on). Off, a region that cannot coarsen is regenerated and refused at
    /// every pass, as before.
    pub delay_refused_simplification: bool,
    /// A simplification patch with no fewer faces than its region is regenerated coarser (the density
    /// lowered 5 % a generation, within the edge-length rules and the retry cap), and when no
    /// generation both has fewer faces and keeps the rules, one vertex of the region is removed and
    /// its star filled without a new point ([`anima_geom::remesh::AdaptiveMesh::remove_vertex`],
    /// within [L⁰_min-rule, L⁰_max]), instead of the guard refusing the attempt (anima's; on). The
    /// thesis meshes a simplified hole once at the border's density; where the border is fine that
    /// density puts back as many interior points as were there (the front places them in steps, so a
    /// density between two counts often gives an edge over L⁰_max), and the guard undid the attempt.
    pub coarsen_simplification: bool,
    /// A refinement patch with no more faces than the region it replaces is refused and the region
    /// restored (anima's; on). Near L⁰_min the mesher, held back by the short-edge rule, can only
    /// regenerate a region at the size it has, while the criteria keep selecting it: every pass then
    /// replaced it by an equal patch, re-interpolating its particles from the old faces. On Test II's
    /// round table (short edges ≥ L⁰_min, RK4) that happened about once a millisecond at the table's
    /// rim, and the cloth crept off the tabletop and fell past it by 0.8 s; with the guard it stays
    /// on the table, as the uniform meshes and the thesis's figures do.
    pub refuse_idle_refinement: bool,
    /// Time between remeshing passes, s; 0 remeshes after every step as the thesis does (Fig. 4.1).
    pub interval_s: f64,
    /// cast every edge that may no longer be refined (L⁰ < L⁰_min) at the end of each step and
    /// answer a hit on both its ends as particle hits, as the thesis does to reduce visible
    /// intersections. On by default.
    pub repel_unrefinable_edges: bool,
}

impl OliveiraRemeshing {
    fn common(l_min: f64, l_max: f64, t_simp: f64, c2: f64, d_simp: f64) -> Self {
        Self {
            compression: 0.7,
            cos_refine: 0.97,
            cos_simplify: 0.999995,
            cos_collision_guard: 0.97,
            min_rest_length: l_min,
            max_rest_length: l_max,
            time_to_simplify: t_simp,
            smoothing_ratio: c2,
            density_refine: 1.01,
            density_simplify: d_simp,
            curvature_limit: CurvatureLimit::Clamped,
            short_edge: ShortEdgeRule::LiteralSquare,
            max_tries: 50,
            improvement_rounds: 3,
            simplify: true,
            delay_refused_simplification: true,
            coarsen_simplification: true,
            refuse_idle_refinement: true,
            interval_s: 0.0,
            repel_unrefinable_edges: true,
        }
    }

    /// Table 5.1 (Test I, the Bunny).
    pub fn test_1() -> Self {
        Self::common(0.13, 0.40, 0.1, 0.75, 0.75)
    }

    /// Table 5.3 (Test II, the round table).
    pub fn test_2() -> Self {
        Self::common(0.10, 0.35, 0.02, 0.65, 0.25)
    }

    /// Table 5.5 (Test III, the sphere).
    pub fn test_3() -> Self {
        Self::common(0.08, 0.25, 0.1, 0.75, 0.35)
    }

    /// A⁰_max = (√3/4)(L⁰_max)².
    pub fn max_rest_area(&self) -> f64 {
        3f64.sqrt() / 4.0 * self.max_rest_length * self.max_rest_length
    }

    /// Whether an edge of rest length `l0` may still be refined.
    pub fn can_refine(&self, l0: f64) -> bool {
        l0 >= self.min_rest_length
    }

    /// The length below which no generated edge may fall: a patch with a shorter one is regenerated,
    /// and refused when no retry avoids it.
    pub fn short_edge_limit(&self) -> f64 {
        match self.short_edge {
            ShortEdgeRule::LiteralSquare => self.min_rest_length * self.min_rest_length,
            ShortEdgeRule::MinLength => self.min_rest_length,
        }
    }

    /// The shortest cloth-contour edge a refinement bisects (spec §6.5): L⁰_min, and at least twice
    /// the short-edge limit so that both halves keep it (with `MinLength`, 2·L⁰_min; with the literal
    /// rule the limit is far below L⁰_min and L⁰_min decides).
    pub fn min_bisected_length(&self) -> f64 {
        self.min_rest_length.max(2.0 * self.short_edge_limit())
    }
}

/// An undirected edge of a compacted [`AdaptiveMesh`] with its one or two faces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MeshEdge {
    pub a: u32,
    pub b: u32,
    pub faces: [u32; 2],
    pub n_faces: usize,
}

impl MeshEdge {
    pub fn key(&self) -> (u32, u32) {
        (self.a.min(self.b), self.a.max(self.b))
    }

    pub fn faces(&self) -> &[u32] {
        &self.faces[..self.n_faces]
    }
}

/// Every live edge once, in the mesh's deterministic order.
pub(crate) fn mesh_edges(mesh: &AdaptiveMesh) -> Vec<MeshEdge> {
    mesh.edges()
        .into_iter()
        .map(|(h, a, b)| {
            let other = mesh.find_half_edge(b, a).filter(|&g| g != h);
            match other {
                Some(g) => MeshEdge { a, b, faces: [h / 3, g / 3], n_faces: 2 },
                None => MeshEdge { a, b, faces: [h / 3, h / 3], n_faces: 1 },
            }
        })
        .collect()
}

/// Unit vertex normals per vertex slot (sum of unit face normals, normalised; Q-8).
pub(crate) fn mesh_vertex_normals(mesh: &AdaptiveMesh) -> Vec<DVec3> {
    let mut n = vec![DVec3::ZERO; mesh.n_vertex_slots()];
    vertex_normals(&mesh.triangles(), mesh.positions(), &mut n);
    n
}

/// Whether a colliding edge passes the angle guard: the mean normal of its faces is not within
/// θ_guard of the object's normal at the hit.
pub(crate) fn collision_refines(
    mesh: &AdaptiveMesh,
    colliders: &[Collider],
    e: &MeshEdge,
    cos_guard: f64,
) -> Option<bool> {
    let x = mesh.positions();
    let (_, normal, _) = first_hit(colliders, x[e.a as usize], x[e.b as usize])?;
    let cloth: DVec3 = e.faces().iter().map(|&f| mesh.world_normal(f)).sum();
    let cloth = cloth.normalize_or_zero();
    Some(cloth.dot(normal).abs() < cos_guard)
}

/// What the criteria chose, as edge keys (vertex pairs, smaller first).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Selection {
    pub refine: Vec<(u32, u32)>,
    pub simplify: Vec<(u32, u32)>,
    /// Refine edges picked by each criterion before smoothing: compression, collision, curvature.
    pub by_criterion: [usize; 3],
    /// Colliding edges that may no longer be refined (L⁰ < L⁰_min).
    pub colliding_unrefinable: Vec<(u32, u32)>,
}

/// Runs the three criteria and both smoothing passes on a compacted mesh at time `t`. `refined_at`
/// gives the time each edge was made by a refinement (edges not in it are old).
pub fn select_edges(
    mesh: &AdaptiveMesh,
    colliders: &[Collider],
    refined_at: &BTreeMap<(u32, u32), f64>,
    t: f64,
    p: &OliveiraRemeshing,
) -> Selection {
    let edges = mesh_edges(mesh);
    let normals = mesh_vertex_normals(mesh);
    let rest = mesh.rest();
    let x = mesh.positions();
    let a_max = p.max_rest_area();
    let rest_len = |e: &MeshEdge| rest[e.a as usize].distance(rest[e.b as usize]);
    let age = |k: (u32, u32)| refined_at.get(&k).map_or(f64::INFINITY, |&t0| t - t0);
    // 0 keep, 1 refine, 2 simplify.
    let mut mark = vec![0u8; edges.len()];
    let mut out = Selection::default();
    for (i, e) in edges.iter().enumerate() {
        let l0 = rest_len(e);
        let can_refine = p.can_refine(l0);
        let can_simplify = p.simplify && l0 <= p.max_rest_length && age(e.key()) >= p.time_to_simplify;
        let (xa, xb) = (x[e.a as usize], x[e.b as usize]);
        if can_refine && xa.distance(xb) / l0 < p.compression {
            mark[i] = 1;
            out.by_criterion[0] += 1;
            continue;
        }
        match collision_refines(mesh, colliders, e, p.cos_collision_guard) {
            Some(true) if can_refine => {
                mark[i] = 1;
                out.by_criterion[1] += 1;
                continue;
            }
            Some(_) if !can_refine => out.colliding_unrefinable.push(e.key()),
            _ => {}
        }
        let cos = normals[e.a as usize].dot(normals[e.b as usize]);
        let mean_area = e.faces().iter().map(|&f| mesh.rest_area(f)).sum::<f64>() / e.n_faces as f64;
        let ratio = mean_area / a_max;
        let limit = p.cos_refine
            * match p.curvature_limit {
                CurvatureLimit::Clamped => ratio.min(1.0),
                CurvatureLimit::Literal => ratio,
            };
        if can_refine && cos < limit {
            mark[i] = 1;
            out.by_criterion[2] += 1;
        } else if can_simplify && cos > p.cos_simplify {
            mark[i] = 2;
        }
    }
    // Smoothing: one pass over the criteria's choices (spec §6.3).
    let mut face_edges: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
    for (i, e) in edges.iter().enumerate() {
        for &f in e.faces() {
            face_edges.entry(f).or_default().push(i);
        }
    }
    let chosen = mark.clone();
    for (i, e) in edges.iter().enumerate() {
        if chosen[i] == 0 {
            continue;
        }
        let li = rest_len(e);
        for f in e.faces() {
            for &j in &face_edges[f] {
                if j == i || mark[j] != 0 {
                    continue;
                }
                let lj = rest_len(&edges[j]);
                if chosen[i] == 1 && li / lj < p.smoothing_ratio && lj >= p.min_rest_length {
                    mark[j] = 1;
                } else if chosen[i] == 2
                    && lj <= p.max_rest_length
                    && age(edges[j].key()) >= 0.1 * p.time_to_simplify
                {
                    mark[j] = 2;
                }
            }
        }
    }
    for (i, e) in edges.iter().enumerate() {
        match mark[i] {
            1 => out.refine.push(e.key()),
            2 => out.simplify.push(e.key()),
            _ => {}
        }
    }
    out
}

/// The face-connected components of a set of edges (two edges are adjacent when they share a face), as
/// sorted face lists, ordered by their smallest face. Faces listed in `exclude` drop the edges touching
/// them.
pub fn edge_components(mesh: &AdaptiveMesh, keys: &[(u32, u32)], exclude: &[u32]) -> Vec<Vec<u32>> {
    let edges: Vec<MeshEdge> = mesh_edges(mesh);
    let index: BTreeMap<(u32, u32), usize> = edges.iter().enumerate().map(|(i, e)| (e.key(), i)).collect();
    let mut parent: BTreeMap<u32, u32> = BTreeMap::new();
    fn find(parent: &mut BTreeMap<u32, u32>, f: u32) -> u32 {
        let mut r = f;
        while parent[&r] != r {
            r = parent[&r];
        }
        let mut c = f;
        while parent[&c] != r {
            let next = parent[&c];
            parent.insert(c, r);
            c = next;
        }
        r
    }
    for k in keys {
        let Some(&i) = index.get(k) else { continue };
        let faces = edges[i].faces();
        if faces.iter().any(|f| exclude.binary_search(f).is_ok()) {
            continue;
        }
        for &f in faces {
            parent.entry(f).or_insert(f);
        }
        let (ra, rb) = (find(&mut parent, faces[0]), find(&mut parent, faces[faces.len() - 1]));
        if ra != rb {
            parent.insert(ra.max(rb), ra.min(rb));
        }
    }
    let all: Vec<u32> = parent.keys().copied().collect();
    let mut groups: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for f in all {
        let r = find(&mut parent, f);
        groups.entry(r).or_default().push(f);
    }
    groups.into_values().collect()
}

/// The edges of a face list as sorted keys.
pub(crate) fn face_edge_keys(mesh: &AdaptiveMesh, faces: &[u32]) -> Vec<(u32, u32)> {
    let mut out: Vec<(u32, u32)> = faces
        .iter()
        .flat_map(|&f| {
            let [a, b, c] = mesh.face_slots()[f as usize];
            [(a, b), (b, c), (c, a)]
        })
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// Barycentric interpolation of per-vertex `values` at material point `p` over `triangles` with rest
/// coordinates `rest`; the nearest triangle (by barycentric slack) when `p` lies in none.
pub fn interpolate_at(rest: &[DVec2], triangles: &[[u32; 3]], values: &[DVec3], p: DVec2) -> DVec3 {
    let mut best = (f64::NEG_INFINITY, DVec3::ZERO);
    for t in triangles {
        let [a, b, c] = t.map(|i| rest[i as usize]);
        let d = (b - a).perp_dot(c - a);
        if d == 0.0 {
            continue;
        }
        let w1 = (p - a).perp_dot(c - a) / d;
        let w2 = (b - a).perp_dot(p - a) / d;
        let w0 = 1.0 - w1 - w2;
        let slack = w0.min(w1).min(w2);
        if slack > best.0 {
            let v = values[t[0] as usize] * w0 + values[t[1] as usize] * w1 + values[t[2] as usize] * w2;
            best = (slack, v);
            if slack >= 0.0 {
                break;
            }
        }
    }
    best.1
}

#[cfg(test)]
mod tests;
