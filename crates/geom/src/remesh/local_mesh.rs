//! The planar local mesh generator of spec §6.6 (Oliveira 2013 §4.5.4, after Miranda, Cavalcante-Neto
//! & Martha 1999): given the border of a hole in rest space, fill it with triangles that use exactly the
//! border's vertices on the border.
//!
//! 1. **Quadtree sizing.** A quadtree over the border is refined until the cell holding each border
//!    edge is no larger than that edge's target size; then no interior cell may be larger than the
//!    largest border cell, and neighbouring cells differ by at most one level. The size at a point is
//!    the side of its cell, which grades smoothly from the border inwards.
//! 2. **Advancing front.** The shortest front edge is taken first; its ideal apex sits where both new
//!    edges have the local size. Front vertices near the ideal apex are preferred to a new vertex
//!    (the geometric phase); if no candidate passes the checks (positive area, no crossing of the
//!    front, no front vertex inside, apex inside the region) every front vertex is tried, best shape
//!    first (the topological phase).
//! 3. **Improvement.** Delaunay flips of interior edges remove bad triangles, and Laplacian smoothing
//!    moves each new vertex to the mean of its neighbours when that keeps every triangle proper.
//!
//! The size rule follows the spec's reconstruction (spec reconstruction) of the density factor's direction: the
//! target size of border edge j is h_j = L⁰_j·0.85/d, so a larger density d means a finer mesh.
//! [`mesh_hole_with_retries`] adds the thesis's retry loop (spec §6.6, A-38).

use std::collections::BTreeMap;

use glam::DVec2;

use super::mesh::{cross2, is_proper};

/// How large the new triangles should be.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MeshSize {
    /// One target edge length everywhere, m.
    Uniform(f64),
    /// Oliveira's density factor d (spec §6.4, §6.6 (spec reconstruction)): border edge j asks for h_j = L⁰_j·0.85/d.
    Density(f64),
}

/// The generator's knobs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalMeshParams {
    pub size: MeshSize,
    /// Rounds of (flips, Laplacian smoothing) after the front closes.
    pub improvement_rounds: usize,
}

impl LocalMeshParams {
    pub const fn new(size: MeshSize) -> Self {
        Self { size, improvement_rounds: 5 }
    }
}

/// A filled hole: `points[..n_border]` are the border points in the order given (loops concatenated),
/// the rest are new interior points; triangles are counter-clockwise.
#[derive(Debug, Clone, PartialEq)]
pub struct HoleMesh {
    pub points: Vec<DVec2>,
    pub n_border: usize,
    /// Where each border loop starts in `points` (the first at 0).
    pub loop_starts: Vec<usize>,
    pub triangles: Vec<[u32; 3]>,
}

impl HoleMesh {
    pub fn n_interior(&self) -> usize {
        self.points.len() - self.n_border
    }

    /// Shortest edge, m.
    pub fn min_edge(&self) -> f64 {
        self.triangles
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .map(|(a, b)| self.points[a as usize].distance(self.points[b as usize]))
            .fold(f64::INFINITY, f64::min)
    }

    /// Smallest interior angle over all triangles, rad.
    pub fn min_angle(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| min_angle(t.map(|i| self.points[i as usize])))
            .fold(f64::INFINITY, f64::min)
    }

    pub fn area(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                0.5 * cross2(
                    self.points[t[0] as usize],
                    self.points[t[1] as usize],
                    self.points[t[2] as usize],
                )
            })
            .sum()
    }
}

fn min_angle(p: [DVec2; 3]) -> f64 {
    (0..3)
        .map(|k| {
            let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
            (b - a).angle_to(c - a).abs()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Why a hole could not be meshed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LocalMeshError {
    #[error("the border is not a set of closed loops with positive total area (loop {0})")]
    BadBorder(usize),
    #[error("the advancing front got stuck with {0} front edges left")]
    Stuck(usize),
    #[error("the target size must be positive and finite")]
    BadSize,
    #[error("no patch passed the retry rule in {0} generations; the hole is refused")]
    Refused(usize),
}

/// Signed area of a closed polygon.
pub fn polygon_area(points: &[DVec2]) -> f64 {
    let n = points.len();
    (0..n).map(|i| points[i].perp_dot(points[(i + 1) % n])).sum::<f64>() * 0.5
}

struct Quadtree {
    centre: Vec<DVec2>,
    half: Vec<f64>,
    child: Vec<u32>,
}

impl Quadtree {
    fn new(min: DVec2, max: DVec2) -> Self {
        let half = 0.5 * (max - min).max_element() * 1.001 + 1e-300;
        Self { centre: vec![0.5 * (min + max)], half: vec![half], child: vec![u32::MAX] }
    }

    fn split(&mut self, c: usize) {
        let first = self.centre.len() as u32;
        let h = 0.5 * self.half[c];
        for (dx, dy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
            self.centre.push(self.centre[c] + DVec2::new(dx * h, dy * h));
            self.half.push(h);
            self.child.push(u32::MAX);
        }
        self.child[c] = first;
    }

    fn leaf(&self, p: DVec2) -> usize {
        let mut c = 0;
        while self.child[c] != u32::MAX {
            let o = p - self.centre[c];
            c = self.child[c] as usize + usize::from(o.x >= 0.0) + 2 * usize::from(o.y >= 0.0);
        }
        c
    }

    fn refine_at(&mut self, p: DVec2, size: f64) {
        loop {
            let c = self.leaf(p);
            if 2.0 * self.half[c] <= size {
                return;
            }
            self.split(c);
        }
    }

    fn size(&self, p: DVec2) -> f64 {
        2.0 * self.half[self.leaf(p)]
    }

    fn leaves(&self) -> Vec<usize> {
        (0..self.child.len()).filter(|&c| self.child[c] == u32::MAX).collect()
    }
}

/// Winding number of the front (a set of closed directed loops) around p.
fn winding(points: &[DVec2], front: &[(u32, u32)], alive: &[bool], p: DVec2) -> i32 {
    let mut w = 0;
    for (i, &(a, b)) in front.iter().enumerate() {
        if !alive[i] {
            continue;
        }
        let (pa, pb) = (points[a as usize], points[b as usize]);
        if pa.y <= p.y {
            if pb.y > p.y && cross2(pa, pb, p) > 0.0 {
                w += 1;
            }
        } else if pb.y <= p.y && cross2(pa, pb, p) < 0.0 {
            w -= 1;
        }
    }
    w
}

/// Whether segments pq and rs cross at a point interior to both (touching at shared ends does not
/// count; collinear overlap does).
fn segments_cross(p: DVec2, q: DVec2, r: DVec2, s: DVec2) -> bool {
    let d1 = cross2(p, q, r);
    let d2 = cross2(p, q, s);
    let d3 = cross2(r, s, p);
    let d4 = cross2(r, s, q);
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    // Collinear overlap.
    let on = |a: DVec2, b: DVec2, c: DVec2| {
        cross2(a, b, c).abs() <= 1e-14 * (b - a).length_squared()
            && (c - a).dot(b - a) > 0.0
            && (c - b).dot(a - b) > 0.0
    };
    on(p, q, r) || on(p, q, s) || on(r, s, p) || on(r, s, q)
}

fn point_in_triangle(a: DVec2, b: DVec2, c: DVec2, p: DVec2) -> bool {
    cross2(a, b, p) > 0.0 && cross2(b, c, p) > 0.0 && cross2(c, a, p) > 0.0
}

/// Meshes the region bounded by `loops` (each a closed polygon, the region on its left: outer borders
/// counter-clockwise, islands clockwise), using every border point and no other point on the border.
pub fn mesh_hole(loops: &[Vec<DVec2>], params: &LocalMeshParams) -> Result<HoleMesh, LocalMeshError> {
    let mut points: Vec<DVec2> = Vec::new();
    let mut front: Vec<(u32, u32)> = Vec::new();
    let mut total = 0.0;
    let mut loop_starts = Vec::with_capacity(loops.len());
    for (i, l) in loops.iter().enumerate() {
        if l.len() < 3 || l.iter().any(|p| !p.is_finite()) {
            return Err(LocalMeshError::BadBorder(i));
        }
        let base = points.len() as u32;
        let n = l.len() as u32;
        loop_starts.push(points.len());
        points.extend_from_slice(l);
        front.extend((0..n).map(|k| (base + k, base + (k + 1) % n)));
        total += polygon_area(l);
    }
    if total.is_nan() || total <= 0.0 {
        return Err(LocalMeshError::BadBorder(0));
    }
    let n_border = points.len();
    let target = |len: f64| match params.size {
        MeshSize::Uniform(h) => h,
        MeshSize::Density(d) => len * 0.85 / d,
    };
    let bad_size = match params.size {
        MeshSize::Uniform(h) => h.is_nan() || h <= 0.0 || h.is_infinite(),
        MeshSize::Density(d) => d.is_nan() || d <= 0.0 || d.is_infinite(),
    };
    if bad_size {
        return Err(LocalMeshError::BadSize);
    }
    // 1. Quadtree sizing.
    let (lo, hi) = points
        .iter()
        .fold((DVec2::splat(f64::MAX), DVec2::splat(f64::MIN)), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let mut qt = Quadtree::new(lo, hi);
    let mut max_border = 0.0f64;
    for &(a, b) in &front {
        let (pa, pb) = (points[a as usize], points[b as usize]);
        let h = target(pa.distance(pb));
        for p in [pa, 0.5 * (pa + pb), pb] {
            qt.refine_at(p, h);
        }
    }
    let mut max_target = 0.0f64;
    for &(a, b) in &front {
        let (pa, pb) = (points[a as usize], points[b as usize]);
        max_border = max_border.max(qt.size(0.5 * (pa + pb)));
        max_target = max_target.max(target(pa.distance(pb)));
    }
    // Cell sides are the root's side over powers of two, up to twice smaller than asked; one scale
    // factor maps them back onto the requested sizes.
    let scale = (max_target / max_border).clamp(1.0, 2.0);
    let all_alive = vec![true; front.len()];
    loop {
        let mut changed = false;
        for c in qt.leaves() {
            let inside = winding(&points, &front, &all_alive, qt.centre[c]) != 0;
            if inside && 2.0 * qt.half[c] > max_border * (1.0 + 1e-9) {
                qt.split(c);
                changed = true;
            }
        }
        // 2:1 balance.
        for c in qt.leaves() {
            let (ctr, h) = (qt.centre[c], qt.half[c]);
            for d in [DVec2::X, DVec2::NEG_X, DVec2::Y, DVec2::NEG_Y] {
                let q = ctr + d * (h * 1.01);
                let n = qt.leaf(q);
                if qt.half[n] > 2.0 * h * (1.0 + 1e-9) && (q - qt.centre[0]).abs().max_element() < qt.half[0]
                {
                    qt.split(n);
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    // 2. Advancing front.
    let mut alive = vec![true; front.len()];
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut n_alive = front.len();
    let cells = (total / (max_border * max_border)).ceil() as usize;
    let max_steps = 20 * (front.len() + 4 * qt.leaves().len().max(cells) + 10);
    let mut steps = 0;
    while n_alive > 0 {
        steps += 1;
        if steps > max_steps {
            return Err(LocalMeshError::Stuck(n_alive));
        }
        // Shortest live front edge (first in order among equals).
        let mut best = usize::MAX;
        let mut best_len = f64::INFINITY;
        for (i, &(a, b)) in front.iter().enumerate() {
            if alive[i] {
                let l = points[a as usize].distance_squared(points[b as usize]);
                if l < best_len {
                    best_len = l;
                    best = i;
                }
            }
        }
        let (a, b) = front[best];
        let (pa, pb) = (points[a as usize], points[b as usize]);
        let len = best_len.sqrt();
        let mid = 0.5 * (pa + pb);
        let normal = (pb - pa).perp() / len;
        let d = (scale * qt.size(mid)).clamp(0.55 * len, 2.0 * len);
        let height = (d * d - 0.25 * len * len).max(0.0).sqrt();
        let ideal = mid + normal * height;
        // Geometric phase: front vertices near the ideal apex, then the apex itself.
        let radius = 0.7 * d;
        let mut cand: Vec<(f64, u32)> = Vec::new();
        let mut front_vertices: Vec<u32> =
            front.iter().zip(&alive).filter(|(_, l)| **l).map(|(e, _)| e.0).collect();
        front_vertices.sort_unstable();
        front_vertices.dedup();
        for &c in &front_vertices {
            if c != a && c != b && cross2(pa, pb, points[c as usize]) > 0.0 {
                let dist = points[c as usize].distance(ideal);
                if dist < radius {
                    cand.push((dist, c));
                }
            }
        }
        cand.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        let new_id = points.len() as u32;
        let too_close = cand.first().is_some_and(|c| c.0 < 0.55 * d);
        if !too_close {
            cand.insert(0, (0.0, new_id));
        }
        points.push(ideal);
        let valid = |c: u32, points: &[DVec2], alive: &[bool]| -> bool {
            let pc = points[c as usize];
            if !is_proper(pa, pb, pc) || min_angle([pa, pb, pc]) < 1e-3 {
                return false;
            }
            for (i, &(e0, e1)) in front.iter().enumerate() {
                if !alive[i] {
                    continue;
                }
                let (q0, q1) = (points[e0 as usize], points[e1 as usize]);
                if (e0 != a && e1 != a && e0 != c && e1 != c && segments_cross(pa, pc, q0, q1))
                    || (e0 != b && e1 != b && e0 != c && e1 != c && segments_cross(pc, pb, q0, q1))
                {
                    return false;
                }
                if e0 != a && e0 != b && e0 != c && point_in_triangle(pa, pb, pc, q0) {
                    return false;
                }
                if c == new_id {
                    // A new vertex keeps clear of the front: no slivers against other edges.
                    let t = ((pc - q0).dot(q1 - q0) / (q1 - q0).length_squared()).clamp(0.0, 1.0);
                    if (q0 + (q1 - q0) * t).distance(pc) < 0.4 * d {
                        return false;
                    }
                }
            }
            c != new_id || winding(points, &front, alive, pc) != 0
        };
        // Of the valid candidates, the best-shaped triangle wins; closing the front with an existing
        // vertex gets a small bonus, since it makes the front shorter.
        let mut chosen = None;
        let mut best_q = f64::NEG_INFINITY;
        for &(_, c) in &cand {
            if valid(c, &points, &alive) {
                let q = min_angle([pa, pb, points[c as usize]]) * if c == new_id { 1.0 } else { 1.15 };
                if q > best_q {
                    best_q = q;
                    chosen = Some(c);
                }
            }
        }
        if chosen.is_none() {
            // Topological phase: any front vertex, best-shaped triangle first.
            let mut all: Vec<(f64, u32)> = front_vertices
                .iter()
                .filter(|&&c| c != a && c != b && cross2(pa, pb, points[c as usize]) > 0.0)
                .map(|&c| (-min_angle([pa, pb, points[c as usize]]), c))
                .collect();
            all.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            chosen = all.iter().map(|c| c.1).find(|&c| valid(c, &points, &alive));
        }
        let Some(c) = chosen else {
            return Err(LocalMeshError::Stuck(n_alive));
        };
        if c != new_id {
            points.pop();
        }
        triangles.push([a, b, c]);
        alive[best] = false;
        n_alive -= 1;
        for (p, q) in [(a, c), (c, b)] {
            // Close the edge if the front already runs the other way, else open it.
            if let Some(i) = front.iter().zip(&alive).position(|(e, &l)| l && *e == (q, p)) {
                alive[i] = false;
                n_alive -= 1;
            } else {
                front.push((p, q));
                alive.push(true);
                n_alive += 1;
            }
        }
    }
    let mut mesh = HoleMesh { points, n_border, loop_starts, triangles };
    for _ in 0..params.improvement_rounds {
        delaunay_flips(&mut mesh);
        smooth(&mut mesh);
    }
    delaunay_flips(&mut mesh);
    Ok(mesh)
}

/// Flips interior edges of the patch whose two opposite angles sum to more than π, when the quad is
/// convex: this removes the worst triangles the front left behind.
fn delaunay_flips(mesh: &mut HoleMesh) {
    for _ in 0..8 {
        let mut edges: BTreeMap<(u32, u32), (usize, usize)> = BTreeMap::new();
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                edges.insert((tri[k], tri[(k + 1) % 3]), (t, k));
            }
        }
        let mut flipped = vec![false; mesh.triangles.len()];
        let mut any = false;
        for (&(a, b), &(t, k)) in &edges {
            if a > b {
                continue;
            }
            let Some(&(u, m)) = edges.get(&(b, a)) else { continue };
            if flipped[t] || flipped[u] {
                continue;
            }
            let c = mesh.triangles[t][(k + 2) % 3];
            let d = mesh.triangles[u][(m + 2) % 3];
            let p = |i: u32| mesh.points[i as usize];
            let (ca, cb, da, db) = (p(a) - p(c), p(b) - p(c), p(a) - p(d), p(b) - p(d));
            let cot = ca.dot(cb) / ca.perp_dot(cb).abs() + da.dot(db) / da.perp_dot(db).abs();
            if cot < -1e-9 && is_proper(p(c), p(a), p(d)) && is_proper(p(d), p(b), p(c)) {
                mesh.triangles[t] = [c, a, d];
                mesh.triangles[u] = [d, b, c];
                flipped[t] = true;
                flipped[u] = true;
                any = true;
            }
        }
        if !any {
            break;
        }
    }
}

/// One Laplacian pass over the interior points: each moves to the mean of its neighbours if every
/// incident triangle stays proper and its smallest angle does not drop.
fn smooth(mesh: &mut HoleMesh) {
    let n = mesh.points.len();
    let mut nbrs: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut incident: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            nbrs[tri[k] as usize].push(tri[(k + 1) % 3]);
            incident[tri[k] as usize].push(t);
        }
    }
    for v in mesh.n_border..n {
        if nbrs[v].is_empty() {
            continue;
        }
        let mean = nbrs[v].iter().map(|&w| mesh.points[w as usize]).sum::<DVec2>() / nbrs[v].len() as f64;
        let worst = |mesh: &HoleMesh| {
            incident[v]
                .iter()
                .map(|&t| min_angle(mesh.triangles[t].map(|i| mesh.points[i as usize])))
                .fold(f64::INFINITY, f64::min)
        };
        let before = worst(mesh);
        let old = mesh.points[v];
        mesh.points[v] = mean;
        let ok = incident[v].iter().all(|&t| {
            let [a, b, c] = mesh.triangles[t].map(|i| mesh.points[i as usize]);
            is_proper(a, b, c)
        }) && worst(mesh) >= before;
        if !ok {
            mesh.points[v] = old;
        }
    }
}

/// Ear clipping of one simple counter-clockwise loop: always succeeds, adds no point. The last resort
/// when the front cannot close.
pub fn ear_clip(points: &[DVec2]) -> Option<Vec<[u32; 3]>> {
    let mut idx: Vec<u32> = (0..points.len() as u32).collect();
    let mut tris = Vec::with_capacity(points.len().saturating_sub(2));
    while idx.len() > 3 {
        let n = idx.len();
        let mut best: Option<(f64, usize)> = None;
        for i in 0..n {
            let (a, b, c) = (idx[(i + n - 1) % n], idx[i], idx[(i + 1) % n]);
            let (pa, pb, pc) = (points[a as usize], points[b as usize], points[c as usize]);
            if !is_proper(pa, pb, pc) {
                continue;
            }
            let blocked = idx.iter().any(|&o| {
                o != a && o != b && o != c && {
                    let q = points[o as usize];
                    cross2(pa, pb, q) >= 0.0 && cross2(pb, pc, q) >= 0.0 && cross2(pc, pa, q) >= 0.0
                }
            });
            if !blocked {
                let q = min_angle([pa, pb, pc]);
                if best.is_none_or(|(bq, _)| q > bq) {
                    best = Some((q, i));
                }
            }
        }
        let (_, i) = best?;
        let n = idx.len();
        tris.push([idx[(i + n - 1) % n], idx[i], idx[(i + 1) % n]]);
        idx.remove(i);
    }
    let [a, b, c] = [idx[0], idx[1], idx[2]];
    if !is_proper(points[a as usize], points[b as usize], points[c as usize]) {
        return None;
    }
    tris.push([a, b, c]);
    Some(tris)
}

/// The retry rule of spec §6.6/§6.8, and the edge-length bounds every accepted patch keeps.
///
/// The bounds apply to the edges the mesher *generates*: every edge of the patch except the hole's
/// border edges, which exist before the patch and which no density can change (a check that counted
/// them would fail on every try once a short edge sits on the border, and so could never be met).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RetryRule {
    /// Refinement must create at least one interior vertex; if not, d ×= `factor`.
    pub require_interior_vertex: bool,
    /// A patch with a generated edge shorter than this is redone with d ÷= `factor` (the spec's switch
    /// between the literal "(L⁰_min)²" and "L⁰_min" is the caller's choice of this number, Q-9).
    pub short_edge: Option<f64>,
    /// A patch with a generated edge longer than this is redone with d ×= `factor` (L⁰_max for a
    /// simplification: an edge the remesher could never simplify again is not made).
    pub long_edge: Option<f64>,
    /// The refinement percentage (1.01 in the thesis).
    pub factor: f64,
    /// At most this many generations (50 (spec reconstruction)); a hole with no acceptable patch after
    /// them is refused.
    pub max_tries: usize,
    /// A patch with more triangles than this is redone with d ÷= `factor` (a simplification that must
    /// have fewer faces than the region it replaces; checked after the edge lengths).
    pub max_triangles: Option<usize>,
}

impl RetryRule {
    /// The thesis's refinement loop with the given short-edge limit.
    pub const fn refinement(short_edge: Option<f64>) -> Self {
        Self {
            require_interior_vertex: true,
            short_edge,
            long_edge: None,
            factor: 1.01,
            max_tries: 50,
            max_triangles: None,
        }
    }

    /// Simplification as the thesis runs it: one generation, no checks.
    pub const fn simplification() -> Self {
        Self {
            require_interior_vertex: false,
            short_edge: None,
            long_edge: None,
            factor: 1.01,
            max_tries: 1,
            max_triangles: None,
        }
    }

    /// Simplification whose generated edges stay within [`short_edge`, `long_edge`]: the density is
    /// raised (an edge too long) or lowered (one too short) by 5 % for up to 50 generations (a
    /// simplification density can be several times too coarse for `long_edge`: 1.05⁵⁰ ≈ 11).
    pub const fn bounded_simplification(short_edge: Option<f64>, long_edge: Option<f64>) -> Self {
        Self {
            require_interior_vertex: false,
            short_edge,
            long_edge,
            factor: 1.05,
            max_tries: 50,
            max_triangles: None,
        }
    }

    /// Whether `m` may be accepted, and if not which way the density should go.
    fn verdict(&self, m: &HoleMesh) -> Verdict {
        if self.require_interior_vertex && m.n_interior() == 0 {
            return Verdict::Denser;
        }
        let (shortest, longest) = m.generated_edge_range();
        if self.short_edge.is_some_and(|s| shortest < s) {
            Verdict::Coarser
        } else if self.long_edge.is_some_and(|l| longest > l) {
            Verdict::Denser
        } else if self.max_triangles.is_some_and(|n| m.triangles.len() > n) {
            Verdict::Coarser
        } else {
            Verdict::Accept
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Verdict {
    Accept,
    Denser,
    Coarser,
}

impl HoleMesh {
    /// Whether `a`–`b` is an edge of the border: consecutive points of one loop, either way round.
    fn is_border_edge(&self, a: u32, b: u32) -> bool {
        let (a, b) = (a as usize, b as usize);
        if a >= self.n_border || b >= self.n_border {
            return false;
        }
        let k = self.loop_starts.partition_point(|&s| s <= a);
        let start = self.loop_starts[k - 1];
        let end = self.loop_starts.get(k).copied().unwrap_or(self.n_border);
        if !(start..end).contains(&b) {
            return false;
        }
        let (n, i, j) = (end - start, a - start, b - start);
        (i + 1) % n == j || (j + 1) % n == i
    }

    /// Shortest and longest edge the mesher generated (every edge but the border's), m; (∞, 0) when
    /// it generated none.
    pub fn generated_edge_range(&self) -> (f64, f64) {
        let mut out = (f64::INFINITY, 0.0f64);
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if !self.is_border_edge(a, b) {
                    let l = self.points[a as usize].distance(self.points[b as usize]);
                    out = (out.0.min(l), out.1.max(l));
                }
            }
        }
        out
    }
}

/// A patch and how it was obtained.
#[derive(Debug, Clone, PartialEq)]
pub struct RetriedMesh {
    pub mesh: HoleMesh,
    /// Generations run (1 = first try accepted).
    pub tries: usize,
    /// The density finally used.
    pub density: f64,
    /// Whether the patch is an ear clipping of the border (no interior vertex), used when the front
    /// got stuck at every density and the clipping passes the rule.
    pub ear_clipped: bool,
}

/// Meshes a hole at density `d` with the thesis's retry loop: a stuck front, a patch without interior
/// vertex (when required) or with a generated edge outside the rule's bounds is regenerated at
/// d·factor or d/factor. A patch that fails the rule is never returned: when the tries run out the
/// hole is refused ([`LocalMeshError::Refused`]) and the caller leaves the region as it was. Only when
/// the front got stuck at every density is a single loop ear-clipped, and that too only if the
/// clipping passes the rule.
pub fn mesh_hole_with_retries(
    loops: &[Vec<DVec2>],
    density: f64,
    rule: &RetryRule,
    improvement_rounds: usize,
) -> Result<RetriedMesh, LocalMeshError> {
    let mut d = density;
    let max_tries = rule.max_tries.max(1);
    let mut generated_any = false;
    for tries in 1..=max_tries {
        let params = LocalMeshParams { size: MeshSize::Density(d), improvement_rounds };
        match mesh_hole(loops, &params) {
            Ok(m) => {
                generated_any = true;
                match rule.verdict(&m) {
                    Verdict::Accept => {
                        return Ok(RetriedMesh { mesh: m, tries, density: d, ear_clipped: false });
                    }
                    Verdict::Denser => d *= rule.factor,
                    Verdict::Coarser => d /= rule.factor,
                }
            }
            Err(LocalMeshError::Stuck(_)) => d *= rule.factor,
            Err(e) => return Err(e),
        }
    }
    if !generated_any
        && loops.len() == 1
        && let Some(triangles) = ear_clip(&loops[0])
    {
        let mesh =
            HoleMesh { points: loops[0].clone(), n_border: loops[0].len(), loop_starts: vec![0], triangles };
        if rule.verdict(&mesh) == Verdict::Accept {
            return Ok(RetriedMesh { mesh, tries: max_tries, density: d, ear_clipped: true });
        }
    }
    Err(LocalMeshError::Refused(max_tries))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(loops: &[Vec<DVec2>], m: &HoleMesh, what: &str) {
        let area: f64 = loops.iter().map(|l| polygon_area(l)).sum();
        for (t, tri) in m.triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|i| m.points[i as usize]);
            assert!(is_proper(a, b, c), "{what}: triangle {t} is not proper");
        }
        assert!((m.area() - area).abs() <= 1e-12 * area, "{what}: area {} ≠ {area}", m.area());
        // Every border edge is used exactly once, in its direction; no interior point lies on it.
        let mut directed: Vec<(u32, u32)> =
            m.triangles.iter().flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3]))).collect();
        directed.sort_unstable();
        assert!(directed.windows(2).all(|w| w[0] != w[1]), "{what}: an edge is used twice the same way");
        let mut base = 0u32;
        for l in loops {
            let n = l.len() as u32;
            for k in 0..n {
                let e = (base + k, base + (k + 1) % n);
                assert!(directed.binary_search(&e).is_ok(), "{what}: border edge {e:?} is not in the mesh");
            }
            base += n;
        }
        // Every other directed edge has its twin: the patch is a closed disc apart from the border.
        for &(a, b) in &directed {
            let border =
                a < m.n_border as u32 && b < m.n_border as u32 && directed.binary_search(&(b, a)).is_err();
            assert!(border || directed.binary_search(&(b, a)).is_ok(), "{what}: edge ({a}, {b}) has no twin");
        }
    }

    fn square(n: usize, side: f64) -> Vec<DVec2> {
        let mut p = Vec::new();
        for k in 0..n {
            p.push(DVec2::new(side * k as f64 / n as f64, 0.0));
        }
        for k in 0..n {
            p.push(DVec2::new(side, side * k as f64 / n as f64));
        }
        for k in 0..n {
            p.push(DVec2::new(side * (1.0 - k as f64 / n as f64), side));
        }
        for k in 0..n {
            p.push(DVec2::new(0.0, side * (1.0 - k as f64 / n as f64)));
        }
        p
    }

    fn stats(m: &HoleMesh) -> (f64, f64) {
        let angles: Vec<f64> =
            m.triangles.iter().map(|t| min_angle(t.map(|i| m.points[i as usize]))).collect();
        let mean = angles.iter().sum::<f64>() / angles.len() as f64;
        (m.min_angle().to_degrees(), mean.to_degrees())
    }

    #[test]
    fn square_uniform() {
        let loops = vec![square(10, 1.0)];
        let m = mesh_hole(&loops, &LocalMeshParams::new(MeshSize::Uniform(0.1))).unwrap();
        check(&loops, &m, "square");
        let (min, mean) = stats(&m);
        println!(
            "square: {} triangles, {} interior, min angle {min:.1}°, mean min angle {mean:.1}°",
            m.triangles.len(),
            m.n_interior()
        );
        assert!(min > 30.0 && mean > 50.0, "min {min}, mean {mean}");
        assert!((150..=300).contains(&m.triangles.len()), "{}", m.triangles.len());
    }

    #[test]
    fn l_shape_and_density_rule() {
        let l = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(0.5, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 0.5),
            DVec2::new(0.5, 0.5),
            DVec2::new(0.5, 1.0),
            DVec2::new(0.0, 1.0),
            DVec2::new(0.0, 0.5),
        ];
        let loops = vec![l];
        let coarse = mesh_hole(&loops, &LocalMeshParams::new(MeshSize::Density(0.85))).unwrap();
        let fine = mesh_hole(&loops, &LocalMeshParams::new(MeshSize::Density(3.4))).unwrap();
        check(&loops, &coarse, "L coarse");
        check(&loops, &fine, "L fine");
        // A larger density factor gives a finer mesh (spec §6.6 (spec reconstruction)).
        assert!(
            fine.triangles.len() > 3 * coarse.triangles.len(),
            "{} vs {}",
            fine.triangles.len(),
            coarse.triangles.len()
        );
        let (min, mean) = stats(&fine);
        println!("L-shape d = 3.4: {} triangles, min angle {min:.1}°, mean {mean:.1}°", fine.triangles.len());
        assert!(min > 12.0, "{min}");
    }

    #[test]
    fn very_uneven_border_edges() {
        // One long side of 1 m against sides cut into 1/32 m pieces, plus a square island.
        let mut p = vec![DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0)];
        for k in 1..32 {
            p.push(DVec2::new(1.0, k as f64 / 32.0));
        }
        for k in 0..32 {
            p.push(DVec2::new(1.0 - k as f64 / 32.0, 1.0));
        }
        for k in 0..32 {
            p.push(DVec2::new(0.0, 1.0 - k as f64 / 32.0));
        }
        p.dedup();
        let mut island: Vec<DVec2> =
            [(0.4, 0.4), (0.6, 0.4), (0.6, 0.6), (0.4, 0.6)].iter().map(|&(x, y)| DVec2::new(x, y)).collect();
        island.reverse();
        for loops in [vec![p.clone()], vec![p, island]] {
            let m = mesh_hole(&loops, &LocalMeshParams::new(MeshSize::Density(0.85))).unwrap();
            check(&loops, &m, "uneven");
            let (min, mean) = stats(&m);
            println!(
                "uneven ({} loops): {} triangles, min angle {min:.1}°, mean {mean:.1}°",
                loops.len(),
                m.triangles.len()
            );
            assert!(min > 2.0 && mean > 35.0, "{min} {mean}");
        }
    }

    #[test]
    fn retry_loop_forces_an_interior_vertex() {
        // An equilateral hole of three points: d = 0.85 fills it with one triangle; the loop raises d
        // until an interior point appears.
        let loops = vec![vec![DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(0.5, 0.75f64.sqrt())]];
        assert_eq!(
            mesh_hole(&loops, &LocalMeshParams::new(MeshSize::Density(0.85))).unwrap().n_interior(),
            0
        );
        let r = mesh_hole_with_retries(&loops, 0.85, &RetryRule::refinement(None), 3).unwrap();
        check(&loops, &r.mesh, "retry");
        assert!(r.mesh.n_interior() > 0 && r.density > 0.85, "{r:?}");
        let s = mesh_hole_with_retries(&loops, 0.85, &RetryRule::simplification(), 3).unwrap();
        assert_eq!(s.tries, 1);
        let e = ear_clip(&square(3, 1.0)).unwrap();
        assert_eq!(e.len(), 10);
    }

    #[test]
    fn a_triangle_cap_makes_the_loop_coarser() {
        // A square of 12 border points filled densely has interior points; capped below that count,
        // the loop lowers d until a patch with at most the cap comes out, and never returns one over.
        let loops = vec![square(3, 1.0)];
        let dense = mesh_hole_with_retries(&loops, 2.0, &RetryRule::simplification(), 3).unwrap();
        assert!(dense.mesh.n_interior() > 0, "{dense:?}");
        let cap = dense.mesh.triangles.len() - 1;
        let rule = RetryRule { max_triangles: Some(cap), ..RetryRule::bounded_simplification(None, None) };
        let r = mesh_hole_with_retries(&loops, 2.0, &rule, 3).unwrap();
        check(&loops, &r.mesh, "capped");
        assert!(r.mesh.triangles.len() <= cap && r.density < 2.0, "{} > {cap}", r.mesh.triangles.len());
        // A cap under the border's own b − 2 triangles cannot be met.
        let none = RetryRule { max_triangles: Some(9), ..RetryRule::bounded_simplification(None, None) };
        assert_eq!(mesh_hole_with_retries(&loops, 2.0, &none, 3), Err(LocalMeshError::Refused(50)));
    }

    #[test]
    fn a_hole_that_fails_every_retry_is_refused() {
        // Unit equilateral hole: every patch with an interior vertex has edges shorter than 1 m, so a
        // 1.5 m short-edge limit can never be met; nor can an interior vertex be forced in one try at
        // d = 0.85. Neither returns a patch that broke the rule.
        let loops = vec![vec![DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(0.5, 0.75f64.sqrt())]];
        let r = mesh_hole_with_retries(&loops, 2.0, &RetryRule::refinement(Some(1.5)), 3);
        assert_eq!(r, Err(LocalMeshError::Refused(50)));
        let once = RetryRule { max_tries: 1, ..RetryRule::refinement(None) };
        assert_eq!(mesh_hole_with_retries(&loops, 0.85, &once, 3), Err(LocalMeshError::Refused(1)));
        // The same hole with a limit the patch meets is accepted, and its generated edges keep it.
        let ok = mesh_hole_with_retries(&loops, 2.0, &RetryRule::refinement(Some(0.2)), 3).unwrap();
        assert!(ok.mesh.n_interior() > 0 && ok.mesh.generated_edge_range().0 >= 0.2, "{ok:?}");
    }

    #[test]
    fn only_generated_edges_count_against_the_length_bounds() {
        // A 1 m square with a 1 cm border edge: the border is not the mesher's to change, so a 5 cm
        // short-edge limit is read on the edges it generates. Counting the border (as `min_edge` does)
        // would refuse every patch.
        let mut loop0 = vec![DVec2::new(0.0, 0.0), DVec2::new(0.01, 0.0)];
        loop0.extend([DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0), DVec2::new(0.0, 1.0)]);
        let loops = vec![loop0];
        let r = mesh_hole_with_retries(&loops, 0.85, &RetryRule::refinement(Some(0.005)), 3).unwrap();
        check(&loops, &r.mesh, "short border");
        assert!(r.mesh.min_edge() <= 0.01 + 1e-15);
        let (shortest, longest) = r.mesh.generated_edge_range();
        assert!(shortest >= 0.005 && longest > shortest, "{shortest} {longest}");
        // Hand-built: a square loop and a triangular island; the only generated edges are the ones
        // joining them and the square's diagonal, never (3, 4), which joins the two loops' ends.
        let m = HoleMesh {
            points: vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(4.0, 0.0),
                DVec2::new(4.0, 4.0),
                DVec2::new(0.0, 4.0),
                DVec2::new(1.0, 1.0),
                DVec2::new(1.0, 2.0),
                DVec2::new(2.0, 1.0),
            ],
            n_border: 7,
            loop_starts: vec![0, 4],
            triangles: vec![[0, 1, 6], [0, 6, 4], [3, 0, 4], [3, 4, 5], [1, 2, 6], [2, 5, 6], [2, 3, 5]],
        };
        assert!(m.is_border_edge(0, 1) && m.is_border_edge(3, 0) && m.is_border_edge(6, 4));
        assert!(!m.is_border_edge(3, 4) && !m.is_border_edge(0, 2) && !m.is_border_edge(0, 6));
        let (shortest, longest) = m.generated_edge_range();
        assert_eq!(shortest, 2f64.sqrt()); // 0–4
        assert_eq!(longest, 13f64.sqrt()); // 2–5 and 2–6: √(2² + 3²)
    }

    #[test]
    fn bounded_simplification_makes_no_edge_longer_than_its_bound() {
        // A 1 m square cut into 0.1 m border edges, meshed coarsely (d = 0.2 asks for 0.43 m edges):
        // with a 0.3 m bound the density is raised until every generated edge is within it.
        let loops = vec![square(10, 1.0)];
        let free = mesh_hole_with_retries(&loops, 0.2, &RetryRule::simplification(), 3).unwrap();
        assert!(free.mesh.generated_edge_range().1 > 0.3, "{:?}", free.mesh.generated_edge_range());
        let rule = RetryRule::bounded_simplification(None, Some(0.3));
        let bounded = mesh_hole_with_retries(&loops, 0.2, &rule, 3).unwrap();
        check(&loops, &bounded.mesh, "bounded");
        assert!(bounded.mesh.generated_edge_range().1 <= 0.3 && bounded.density > 0.2, "{bounded:?}");
    }
}
