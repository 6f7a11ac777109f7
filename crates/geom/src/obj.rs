//! Wavefront OBJ output (positions and triangles only).

use std::io::{self, Write};

use glam::DVec3;

/// Writes `vertices` and 0-based `triangles` as an OBJ object named `name` (OBJ indices are 1-based).
/// Coordinates are written in the shortest decimal form that reads back to the same `f64`, so a frame
/// file holds the state exactly (a run's `final.obj` can be another run's reference).
pub fn write_obj(
    mut w: impl Write,
    name: &str,
    vertices: &[DVec3],
    triangles: &[[u32; 3]],
) -> io::Result<()> {
    writeln!(w, "# written by anima")?;
    writeln!(w, "o {name}")?;
    for v in vertices {
        writeln!(w, "v {} {} {}", v.x, v.y, v.z)?;
    }
    for [a, b, c] in triangles {
        writeln!(w, "f {} {} {}", a + 1, b + 1, c + 1)?;
    }
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_read_back_exactly() {
        let vertices = vec![
            DVec3::new(0.1, -1.0 / 3.0, 1e-300),
            DVec3::new(std::f64::consts::PI, 123_456_789.123_456_78, -2.5e-7),
            DVec3::new(f64::MIN_POSITIVE, -0.0, 1.0 + f64::EPSILON),
        ];
        let mut out = Vec::new();
        write_obj(&mut out, "t", &vertices, &[[0, 1, 2]]).unwrap();
        let mesh = crate::read_obj(&out[..]).unwrap();
        for (a, b) in mesh.vertices().iter().zip(&vertices) {
            assert_eq!(a.to_array().map(f64::to_bits), b.to_array().map(f64::to_bits), "{a} against {b}");
        }
    }
}
