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
use std::fmt;
use std::io;

use anima_geom::{DVec3, TriangleMesh};

use super::{Animation, UpAxis};
use crate::VizError;

/// Time codes per second: a time code is a millisecond.
pub const TIME_CODES_PER_SECOND: f64 = 1000.0;

impl Animation {
    /// Writes the animation as a USD stage in text form (`.usda`; see [`self::usd`](self) for the
    /// layout). Objects without a frame are left out, as in [`Animation::write_glb`].
    /// The text goes to `w` as it is made, never held whole: a long drape's stage is as large as its
    /// frames.
    pub fn write_usda(&self, w: impl io::Write) -> Result<(), VizError> {
        let mut sink = Sink { w, error: None };
        usda(self, &mut sink);
        match sink.error {
            Some(e) => Err(VizError::UsdWrite(e)),
            None => Ok(()),
        }
    }
}

/// An `io::Write` as the `fmt::Write` the text is made with, keeping the first I/O error (after
/// which nothing more is written).
struct Sink<W> {
    w: W,
    error: Option<io::Error>,
}

impl<W: io::Write> fmt::Write for Sink<W> {
    fn write_str(&mut self, text: &str) -> fmt::Result {
        if self.error.is_some() {
            return Err(fmt::Error);
        }
        self.w.write_all(text.as_bytes()).map_err(|e| {
            self.error = Some(e);
            fmt::Error
        })
    }
}

/// Writes `text`; a failed write is kept by the [`Sink`] and ends the output there.
fn put(s: &mut dyn fmt::Write, text: &str) {
    let _ = s.write_str(text);
}

/// The stage's text, into `s`.
fn usda(anim: &Animation, s: &mut dyn fmt::Write) {
    let up = anim.up;
    let times = (anim.deforming.iter().flat_map(|d| d.times().iter().copied()))
        .chain(anim.remeshed.iter().flat_map(|r| r.frames.iter().map(|f| f.time)))
        .chain(anim.figures.iter().flat_map(|f| f.times.iter().copied()));
    let (start, end) = times.fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), t| (a.min(t), b.max(t)));
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
        open_mesh(s, 1, &names.unique(&o.name), o.colour);
        topology(s, 2, o.mesh.triangles());
        still_points(s, 2, up, &o.mesh);
        put(s, "    }\n");
    }
    for d in anim.deforming.iter().filter(|d| d.n_frames() > 0) {
        open_mesh(s, 1, &names.unique(d.name()), d.colour);
        topology(s, 2, &d.triangles);
        samples(s, up, d.n_frames(), |k| (d.times()[k], d.frame(k)));
        put(s, "    }\n");
    }
    for r in anim.remeshed.iter().filter(|r| r.n_frames() > 0) {
        open_mesh(s, 1, &names.unique(&r.name), r.colour);
        put(s, "        int[] faceVertexCounts.timeSamples = {\n");
        for f in &r.frames {
            let _ = write!(s, "            {}: ", code(f64::from(f.time)));
            bracketed(s, &f.triangles, |s, _| put(s, "3"));
            put(s, ",\n");
        }
        put(s, "        }\n        int[] faceVertexIndices.timeSamples = {\n");
        for f in &r.frames {
            let _ = write!(s, "            {}: ", code(f64::from(f.time)));
            indices(s, &f.triangles);
            put(s, ",\n");
        }
        put(s, "        }\n");
        samples(s, up, r.frames.len(), |k| (r.frames[k].time, &r.frames[k].positions[..]));
        put(s, "    }\n");
    }
    for f in anim.figures.iter().filter(|f| f.n_frames() > 0) {
        let _ = writeln!(s, "    def Xform \"{}\"\n    {{", names.unique(f.name()));
        let mut links = Names::default();
        for (i, link) in f.links().iter().enumerate() {
            let _ = writeln!(s, "        def Xform \"{}\"\n        {{", links.unique(&link.name));
            put(s, "            float3 xformOp:translate.timeSamples = {\n");
            for k in 0..f.n_frames() {
                let p = f.frame(k)[i].translation;
                let _ =
                    writeln!(s, "                {}: {},", code(f64::from(f.times[k])), tuple(&f32s(up, p)));
            }
            put(s, "            }\n            quatf xformOp:orient.timeSamples = {\n");
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
            put(
                s,
                "            }\n            uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:orient\"]\n",
            );
            shape(s, up, &link.shape, link.colour);
            put(s, "        }\n");
        }
        put(s, "    }\n");
    }
    put(s, "}\n");
}

/// A link's shape in its own frame.
fn shape(s: &mut dyn fmt::Write, up: UpAxis, mesh: &TriangleMesh, colour: [u8; 3]) {
    open_mesh(s, 3, "shape", colour);
    topology(s, 4, mesh.triangles());
    still_points(s, 4, up, mesh);
    let _ = writeln!(s, "{}}}", "    ".repeat(3));
}

/// The `extent` and `points` of a mesh that does not move, at `depth` levels of indentation.
fn still_points(s: &mut dyn fmt::Write, depth: usize, up: UpAxis, mesh: &TriangleMesh) {
    let points: Vec<[f32; 3]> = mesh.vertices().iter().map(|p| f32s(up, *p)).collect();
    let pad = "    ".repeat(depth);
    let _ = writeln!(s, "{pad}float3[] extent = {}", extent(&points));
    let _ = write!(s, "{pad}point3f[] points = ");
    list(s, &points);
    put(s, "\n");
}

/// `def Mesh "name"` with its display colour and no subdivision, at `depth` levels of indentation.
fn open_mesh(s: &mut dyn fmt::Write, depth: usize, name: &str, colour: [u8; 3]) {
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
fn topology(s: &mut dyn fmt::Write, depth: usize, triangles: &[[u32; 3]]) {
    let pad = "    ".repeat(depth);
    let _ = write!(s, "{pad}int[] faceVertexCounts = ");
    bracketed(s, triangles, |s, _| put(s, "3"));
    let _ = write!(s, "\n{pad}int[] faceVertexIndices = ");
    indices(s, triangles);
    put(s, "\n");
}

/// Time-sampled `points` and `extent` of a mesh at depth 2: `frame(k)` is frame k's time and positions
/// in the run's axes, turned to y up as they are written.
fn samples<'a>(
    s: &mut dyn fmt::Write,
    up: UpAxis,
    n_frames: usize,
    frame: impl Fn(usize) -> (f32, &'a [[f32; 3]]),
) {
    let turned = |p: &'a [[f32; 3]]| p.iter().map(move |&q| up.to_gltf(q));
    put(s, "        float3[] extent.timeSamples = {\n");
    for k in 0..n_frames {
        let (t, p) = frame(k);
        let box_ = extent(&turned(p).collect::<Vec<_>>());
        let _ = writeln!(s, "            {}: {box_},", code(f64::from(t)));
    }
    put(s, "        }\n        point3f[] points.timeSamples = {\n");
    for k in 0..n_frames {
        let (t, p) = frame(k);
        let _ = write!(s, "            {}: ", code(f64::from(t)));
        bracketed(s, turned(p), |s, q| {
            let _ = write!(s, "({}, {}, {})", q[0], q[1], q[2]);
        });
        put(s, ",\n");
    }
    put(s, "        }\n");
}

/// A time in seconds as a time code.
fn code(t: f64) -> f64 {
    t * TIME_CODES_PER_SECOND
}

fn f32s(up: UpAxis, p: DVec3) -> [f32; 3] {
    up.to_gltf(p.to_array()).map(|v| v as f32)
}

fn tuple(p: &[f32; 3]) -> String {
    format!("({}, {}, {})", p[0], p[1], p[2])
}

/// `[a, b, …]` with each item written by `each`.
fn bracketed<T>(
    s: &mut dyn fmt::Write,
    items: impl IntoIterator<Item = T>,
    each: impl Fn(&mut dyn fmt::Write, T),
) {
    put(s, "[");
    for (k, item) in items.into_iter().enumerate() {
        if k > 0 {
            put(s, ", ");
        }
        each(s, item);
    }
    put(s, "]");
}

fn list(s: &mut dyn fmt::Write, points: &[[f32; 3]]) {
    bracketed(s, points, |s, p| {
        let _ = write!(s, "({}, {}, {})", p[0], p[1], p[2]);
    });
}

fn indices(s: &mut dyn fmt::Write, triangles: &[[u32; 3]]) {
    bracketed(s, triangles, |s, t| {
        let _ = write!(s, "{}, {}, {}", t[0], t[1], t[2]);
    });
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
        let mut text = String::new();
        usda(&anim, &mut text);
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
