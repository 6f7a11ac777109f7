//! Wavefront OBJ output (positions and triangles only).

use std::io::{self, Write};

use glam::DVec3;

/// Writes `vertices` and 0-based `triangles` as an OBJ object named `name` (OBJ indices are 1-based).
pub fn write_obj(
    mut w: impl Write,
    name: &str,
    vertices: &[DVec3],
    triangles: &[[u32; 3]],
) -> io::Result<()> {
    writeln!(w, "# written by anima")?;
    writeln!(w, "o {name}")?;
    for v in vertices {
        writeln!(w, "v {:.6} {:.6} {:.6}", v.x, v.y, v.z)?;
    }
    for [a, b, c] in triangles {
        writeln!(w, "f {} {} {}", a + 1, b + 1, c + 1)?;
    }
    w.flush()
}
