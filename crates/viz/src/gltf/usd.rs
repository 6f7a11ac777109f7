//! The same [`Animation`] as a USD stage in its text form (`.usda`), for film and VFX pipelines, where
//! glTF's morph targets do not scale and cannot change topology.
//!
//! One stage, y up (the run's coordinates turned as for glTF, [`UpAxis::to_gltf`]), metres, a time code
//! per millisecond (`timeCodesPerSecond = 1000`, so a frame's time code is its time in ms and uneven
//! or thinned frames keep their times), `framesPerSecond` the run's mean frame rate. Under the default
//! prim `/anima`:
//!
//! - a static object is a `Mesh` with its points once;
//! - a cloth of fixed topology is a `Mesh` whose `points` and `extent` are time-sampled (its topology
//!   written once);
//! - a remeshed cloth is a `Mesh` whose topology (`faceVertexCounts`, `faceVertexIndices`) is
//!   time-sampled too, as USD allows;
//! - a figure is an `Xform` holding one `Xform` per link with time-sampled `xformOp:translate` and
//!   `xformOp:orient` (the link's world pose, so the links are siblings, not nested by joint) over a
//!   `Mesh` of its shape.
//!
//! Prim names are the objects' names made USD identifiers (letters, digits and `_`, not starting with a
//! digit) and unique among their siblings. Numbers are written as f32 values in their shortest
//! round-trip form, so a reader gets back exactly the positions the glTF file holds.

use std::collections::HashSet;
use std::fmt::Write as _;
use std::io::Write;

use anima_geom::{DVec3, TriangleMesh};

use super::{Animation, UpAxis};
use crate::VizError;

/// Time codes per second: a time code is a millisecond.
pub const TIME_CODES_PER_SECOND: f64 = 1000.0;

impl Animation {
    /// Writes the animation as a USD stage in text form (`.usda`; see [`self::usd`](self) for the
    /// layout). Objects without a frame are left out, as in [`Animation::write_glb`].
    pub fn write_usda(&self, mut w: impl Write) -> Result<(), VizError> {
        let text = usda(self);
        w.write_all(text.as_bytes()).map_err(VizError::UsdWrite)
    }
}

/// The stage's text.
fn usda(anim: &Animation) -> String {
    let up = anim.up;
    let mut times: Vec<f32> = Vec::new();
    for d in anim.deforming.iter().filter(|d| d.n_frames() > 0) {
        times.extend_from_slice(d.times());
    }
    for r in &anim.remeshed {
        times.extend(r.frames.iter().map(|f| f.time));
    }
    for f in anim.figures.iter().filter(|f| f.n_frames() > 0) {
        times.extend_from_slice(&f.times);
    }
    let (start, end) =
        times.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &t| (a.min(t), b.max(t)));
    let (start, end) = if start <= end { (f64::from(start), f64::from(end)) } else { (0.0, 0.0) };
    let frames = anim
        .deforming
        .iter()
        .map(|d| d.n_frames())
        .chain(anim.remeshed.iter().map(|r| r.n_frames()))
        .chain(anim.figures.iter().map(|f| f.n_frames()))
        .max()
        .unwrap_or(0);
    let fps =
        if frames > 1 && end > start { ((frames - 1) as f64 / (end - start)).round().max(1.0) } else { 24.0 };
    let mut s = String::new();
    let _ = write!(
        s,
        "#usda 1.0\n(\n    defaultPrim = \"anima\"\n    doc = \"Written by anima\"\n    endTimeCode = {}\n    \
         framesPerSecond = {fps}\n    metersPerUnit = 1\n    startTimeCode = {}\n    timeCodesPerSecond = {}\n    \
         upAxis = \"Y\"\n)\n\ndef Xform \"anima\" (\n    kind = \"assembly\"\n)\n{{\n",
        code(end),
        code(start),
        TIME_CODES_PER_SECOND
    );
    let mut names = Names::default();
    for o in &anim.statics {
        let points: Vec<[f32; 3]> = o.mesh.vertices().iter().map(|p| f32s(up, *p)).collect();
        open_mesh(&mut s, 1, &names.unique(&o.name), o.colour);
        topology(&mut s, 2, o.mesh.triangles());
        let _ = writeln!(s, "        float3[] extent = {}", extent(&points));
        let _ = writeln!(s, "        point3f[] points = {}", list(&points));
        s.push_str("    }\n");
    }
    for d in anim.deforming.iter().filter(|d| d.n_frames() > 0) {
        open_mesh(&mut s, 1, &names.unique(d.name()), d.colour);
        topology(&mut s, 2, &d.triangles);
        let frames = (0..d.n_frames()).map(|k| (d.times()[k], rotated(up, d.frame(k))));
        samples(&mut s, frames.collect());
        s.push_str("    }\n");
    }
    for r in anim.remeshed.iter().filter(|r| r.n_frames() > 0) {
        open_mesh(&mut s, 1, &names.unique(&r.name), r.colour);
        s.push_str("        int[] faceVertexCounts.timeSamples = {\n");
        for f in &r.frames {
            let _ = writeln!(
                s,
                "            {}: [{}],",
                code(f64::from(f.time)),
                vec!["3"; f.triangles.len()].join(", ")
            );
        }
        s.push_str("        }\n        int[] faceVertexIndices.timeSamples = {\n");
        for f in &r.frames {
            let _ = writeln!(s, "            {}: {},", code(f64::from(f.time)), indices(&f.triangles));
        }
        s.push_str("        }\n");
        samples(&mut s, r.frames.iter().map(|f| (f.time, rotated(up, &f.positions))).collect());
        s.push_str("    }\n");
    }
    for f in anim.figures.iter().filter(|f| f.n_frames() > 0) {
        let _ = writeln!(s, "    def Xform \"{}\"\n    {{", names.unique(f.name()));
        let mut links = Names::default();
        for (i, link) in f.links().iter().enumerate() {
            let _ = writeln!(s, "        def Xform \"{}\"\n        {{", links.unique(&link.name));
            s.push_str("            float3 xformOp:translate.timeSamples = {\n");
            for k in 0..f.n_frames() {
                let p = f.frame(k)[i].translation;
                let _ =
                    writeln!(s, "                {}: {},", code(f64::from(f.times[k])), tuple(&f32s(up, p)));
            }
            s.push_str("            }\n            quatf xformOp:orient.timeSamples = {\n");
            for k in 0..f.n_frames() {
                let q = up.rotation_to_gltf(f.frame(k)[i].rotation);
                let wxyz = [q.w, q.x, q.y, q.z].map(|v| v as f32);
                let _ = writeln!(
                    s,
                    "                {}: ({}, {}, {}, {}),",
                    code(f64::from(f.times[k])),
                    wxyz[0],
                    wxyz[1],
                    wxyz[2],
                    wxyz[3]
                );
            }
            s.push_str(
                "            }\n            uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:orient\"]\n",
            );
            shape(&mut s, up, &link.shape, link.colour);
            s.push_str("        }\n");
        }
        s.push_str("    }\n");
    }
    s.push_str("}\n");
    s
}

/// A link's shape in its own frame.
fn shape(s: &mut String, up: UpAxis, mesh: &TriangleMesh, colour: [u8; 3]) {
    let points: Vec<[f32; 3]> = mesh.vertices().iter().map(|p| f32s(up, *p)).collect();
    open_mesh(s, 3, "shape", colour);
    topology(s, 4, mesh.triangles());
    let pad = "    ".repeat(4);
    let _ = writeln!(s, "{pad}float3[] extent = {}", extent(&points));
    let _ = writeln!(s, "{pad}point3f[] points = {}", list(&points));
    let _ = writeln!(s, "{}}}", "    ".repeat(3));
}

/// `def Mesh "name"` with its display colour and no subdivision, at `depth` levels of indentation.
fn open_mesh(s: &mut String, depth: usize, name: &str, colour: [u8; 3]) {
    let pad = "    ".repeat(depth);
    let c = colour.map(|c| f32::from(c) / 255.0);
    let _ = write!(
        s,
        "{pad}def Mesh \"{name}\"\n{pad}{{\n{pad}    uniform bool doubleSided = 1\n{pad}    color3f[] primvars:displayColor = \
         [({}, {}, {})] (\n{pad}        interpolation = \"constant\"\n{pad}    )\n{pad}    uniform token subdivisionScheme = \
         \"none\"\n",
        c[0], c[1], c[2]
    );
}

/// Triangles as face counts and indices.
fn topology(s: &mut String, depth: usize, triangles: &[[u32; 3]]) {
    let pad = "    ".repeat(depth);
    let _ = writeln!(s, "{pad}int[] faceVertexCounts = [{}]", vec!["3"; triangles.len()].join(", "));
    let _ = writeln!(s, "{pad}int[] faceVertexIndices = {}", indices(triangles));
}

/// Time-sampled `points` and `extent` of a mesh at depth 2.
fn samples(s: &mut String, frames: Vec<(f32, Vec<[f32; 3]>)>) {
    s.push_str("        float3[] extent.timeSamples = {\n");
    for (t, p) in &frames {
        let _ = writeln!(s, "            {}: {},", code(f64::from(*t)), extent(p));
    }
    s.push_str("        }\n        point3f[] points.timeSamples = {\n");
    for (t, p) in &frames {
        let _ = writeln!(s, "            {}: {},", code(f64::from(*t)), list(p));
    }
    s.push_str("        }\n");
}

/// A time in seconds as a time code.
fn code(t: f64) -> f64 {
    t * TIME_CODES_PER_SECOND
}

fn f32s(up: UpAxis, p: DVec3) -> [f32; 3] {
    up.to_gltf(p.to_array()).map(|v| v as f32)
}

fn rotated(up: UpAxis, p: &[[f32; 3]]) -> Vec<[f32; 3]> {
    p.iter().map(|&q| up.to_gltf(q)).collect()
}

fn tuple(p: &[f32; 3]) -> String {
    format!("({}, {}, {})", p[0], p[1], p[2])
}

fn list(points: &[[f32; 3]]) -> String {
    let mut s = String::with_capacity(points.len() * 30 + 2);
    s.push('[');
    for (k, p) in points.iter().enumerate() {
        if k > 0 {
            s.push_str(", ");
        }
        let _ = write!(s, "({}, {}, {})", p[0], p[1], p[2]);
    }
    s.push(']');
    s
}

fn indices(triangles: &[[u32; 3]]) -> String {
    let mut s = String::with_capacity(triangles.len() * 12 + 2);
    s.push('[');
    for (k, t) in triangles.iter().enumerate() {
        if k > 0 {
            s.push_str(", ");
        }
        let _ = write!(s, "{}, {}, {}", t[0], t[1], t[2]);
    }
    s.push(']');
    s
}

/// The bounding box of `points` as USD's `extent`, [(min), (max)].
fn extent(points: &[[f32; 3]]) -> String {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if points.is_empty() {
        (lo, hi) = ([0.0; 3], [0.0; 3]);
    }
    format!("[{}, {}]", tuple(&lo), tuple(&hi))
}

/// Sibling prim names made USD identifiers and unique.
#[derive(Default)]
struct Names(HashSet<String>);

impl Names {
    fn unique(&mut self, name: &str) -> String {
        let mut id: String =
            name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
        if id.is_empty() || id.starts_with(|c: char| c.is_ascii_digit()) {
            id.insert(0, '_');
        }
        let mut candidate = id.clone();
        let mut k = 1;
        while !self.0.insert(candidate.clone()) {
            candidate = format!("{id}_{k}");
            k += 1;
        }
        candidate
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gltf::DeformingMesh;

    #[test]
    fn names_become_unique_identifiers() {
        let mut n = Names::default();
        assert_eq!(n.unique("cloth"), "cloth");
        assert_eq!(n.unique("cloth"), "cloth_1");
        assert_eq!(n.unique("2nd body"), "_2nd_body");
        assert_eq!(n.unique("cortiça"), "corti_a");
        assert_eq!(n.unique(""), "_");
    }

    #[test]
    fn a_deforming_mesh_is_time_sampled_in_y_up_axes() {
        let mut anim = Animation::new(UpAxis::PlusZ);
        let mut d = DeformingMesh::new("sheet", 3, vec![[0, 1, 2]], [255, 0, 0]).unwrap();
        d.push_frame(0.0, &[DVec3::ZERO, DVec3::X, DVec3::Y]).unwrap();
        d.push_frame(0.5, &[DVec3::Z, DVec3::X + DVec3::Z, DVec3::Y + DVec3::Z]).unwrap();
        anim.deforming.push(d);
        let text = usda(&anim);
        assert!(text.starts_with("#usda 1.0\n"));
        for wanted in [
            "defaultPrim = \"anima\"",
            "upAxis = \"Y\"",
            "metersPerUnit = 1",
            "timeCodesPerSecond = 1000",
            "startTimeCode = 0",
            "endTimeCode = 500",
            "framesPerSecond = 2",
            "def Mesh \"sheet\"",
            "int[] faceVertexCounts = [3]",
            "int[] faceVertexIndices = [0, 1, 2]",
            // z up: (x, y, z) is written (x, z, -y).
            "0: [(0, 0, -0), (1, 0, -0), (0, 0, -1)],",
            "500: [(0, 1, -0), (1, 1, -0), (0, 1, -1)],",
            "500: [(0, 1, -1), (1, 1, -0)],",
        ] {
            assert!(text.contains(wanted), "{wanted}:\n{text}");
        }
        let opens = text.matches('{').count();
        assert_eq!(opens, text.matches('}').count(), "balanced braces");
    }
}
