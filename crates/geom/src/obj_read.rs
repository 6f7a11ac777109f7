//! Wavefront OBJ input: vertex positions (`v`) and faces (`f`), enough for static collision meshes.
//!
//! Faces may be polygons (split into a fan of triangles from their first corner) and their corners may
//! carry texture and normal indices (`7/2/7`, `7//7`), which are ignored, as are normals, texture
//! coordinates, groups, objects, smoothing groups and materials. Indices are 1-based; negative ones count
//! back from the last vertex read so far. Every error names the 1-based line and column.

use std::io::{self, BufRead, BufReader, Read};

use glam::DVec3;

use crate::{MeshError, TriangleMesh};

/// What went wrong reading an OBJ file.
#[derive(Debug, thiserror::Error)]
pub enum ObjError {
    #[error("could not read the OBJ data: {0}")]
    Io(#[from] io::Error),
    #[error("{line}:{column}: expected {expected}, found {found}")]
    Syntax { line: usize, column: usize, expected: String, found: String },
    #[error("{line}:{column}: vertex index {index} is out of range (the file has {n_vertices} vertices)")]
    IndexOutOfRange { line: usize, column: usize, index: i64, n_vertices: usize },
    #[error("the file has no faces")]
    NoFaces,
    #[error("the file has no vertices")]
    NoVertices,
    #[error(transparent)]
    Mesh(#[from] MeshError),
}

/// Corners of one face, at most. A polygon of k corners becomes k − 2 triangles from two bytes of file a
/// corner, so without a bound a file of one long polygon costs far more memory per byte than a file of
/// triangles (a 60 MB one-polygon file once took 2.75 GB); real meshes' polygons have a handful.
pub const MAX_FACE_CORNERS: usize = 256;

/// A face corner as written: the 1-based (or negative, relative) index and where it stood.
#[derive(Debug, Clone, Copy)]
struct Corner {
    index: i64,
    line: usize,
    column: usize,
    /// Vertices read before this corner's line, for relative indices.
    n_before: usize,
}

/// Reads positions and faces into a validated [`TriangleMesh`].
pub fn read_obj(r: impl Read) -> Result<TriangleMesh, ObjError> {
    let (vertices, faces) = read_lines(r, true)?;
    if faces.is_empty() {
        return Err(ObjError::NoFaces);
    }
    let n = vertices.len();
    let mut triangles = Vec::with_capacity(faces.len());
    for face in &faces {
        let mut tri = [0u32; 3];
        for (slot, c) in tri.iter_mut().zip(face) {
            let resolved = if c.index > 0 { c.index - 1 } else { c.n_before as i64 + c.index };
            if resolved < 0 || resolved as usize >= n {
                return Err(ObjError::IndexOutOfRange {
                    line: c.line,
                    column: c.column,
                    index: c.index,
                    n_vertices: n,
                });
            }
            *slot = resolved as u32;
        }
        triangles.push(tri);
    }
    Ok(TriangleMesh::new(vertices, triangles)?)
}

/// Reads the vertex positions alone, in file order (a point cloud, or another run's frame to compare
/// with): faces, and every other line, are skipped unread.
pub fn read_obj_positions(r: impl Read) -> Result<Vec<DVec3>, ObjError> {
    let (vertices, _) = read_lines(r, false)?;
    if vertices.is_empty() {
        return Err(ObjError::NoVertices);
    }
    Ok(vertices)
}

/// The vertices and (with `faces`) the faces' triangles as written, checked line by line.
fn read_lines(r: impl Read, want_faces: bool) -> Result<(Vec<DVec3>, Vec<[Corner; 3]>), ObjError> {
    let mut vertices = Vec::new();
    let mut faces: Vec<[Corner; 3]> = Vec::new();
    let mut buf = String::new();
    let mut reader = BufReader::new(r);
    let mut line_no = 0;
    loop {
        buf.clear();
        if reader.read_line(&mut buf)? == 0 {
            break;
        }
        line_no += 1;
        let line = buf.trim_end_matches(['\n', '\r']);
        let content = line.split('#').next().unwrap_or_default();
        let mut tokens = tokens_with_columns(content);
        let Some((_, keyword)) = tokens.next() else { continue };
        let syntax = |column: usize, expected: &str, found: &str| ObjError::Syntax {
            line: line_no,
            column,
            expected: expected.to_owned(),
            found: found.to_owned(),
        };
        let end_column = content.chars().count() + 1;
        match keyword {
            "v" => {
                let mut p = [0.0; 3];
                for (k, value) in p.iter_mut().enumerate() {
                    let (column, text) = tokens.next().ok_or_else(|| {
                        syntax(end_column, &format!("coordinate {} of a vertex", k + 1), "end of line")
                    })?;
                    *value = text
                        .parse::<f64>()
                        .ok()
                        .filter(|x| x.is_finite())
                        .ok_or_else(|| syntax(column, "a finite number", &format!("\"{text}\"")))?;
                }
                // An optional fourth (w) or colour values may follow; they are ignored.
                vertices.push(DVec3::from_array(p));
            }
            "f" if want_faces => {
                let mut corners = Vec::new();
                for (column, text) in tokens {
                    if corners.len() == MAX_FACE_CORNERS {
                        return Err(syntax(
                            column,
                            &format!("at most {MAX_FACE_CORNERS} corners in a face"),
                            "more",
                        ));
                    }
                    let first = text.split('/').next().unwrap_or_default();
                    let index =
                        first.parse::<i64>().ok().filter(|&i| i != 0).ok_or_else(|| {
                            syntax(column, "a non-zero vertex index", &format!("\"{text}\""))
                        })?;
                    corners.push(Corner { index, line: line_no, column, n_before: vertices.len() });
                }
                if corners.len() < 3 {
                    return Err(syntax(
                        end_column,
                        "at least three corners in a face",
                        &format!("{}", corners.len()),
                    ));
                }
                for pair in corners[1..].windows(2) {
                    faces.push([corners[0], pair[0], pair[1]]);
                }
            }
            _ => {} // vn, vt, o, g, s, usemtl, mtllib, l, p, …: not needed for a collision mesh
        }
    }
    Ok((vertices, faces))
}

/// Whitespace-separated tokens with their 1-based character columns.
fn tokens_with_columns(s: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut column = 0;
    let mut rest = s;
    std::iter::from_fn(move || {
        let skip = rest.find(|c: char| !c.is_whitespace())?;
        column += rest[..skip].chars().count();
        rest = &rest[skip..];
        let len = rest.find(char::is_whitespace).unwrap_or(rest.len());
        let token = &rest[..len];
        let start = column + 1;
        column += token.chars().count();
        rest = &rest[len..];
        Some((start, token))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_long_polygon_is_refused_at_its_corner_bound() {
        let mut src: String = (0..300).map(|k| format!("v {k} {} 0\n", k * k)).collect();
        src.push('f');
        for k in 1..=300 {
            src.push_str(&format!(" {k}"));
        }
        let e = read_obj(src.as_bytes()).unwrap_err().to_string();
        assert!(e.starts_with("301:") && e.contains("at most 256 corners in a face"), "{e}");
        // At the bound it is read.
        let cut: String = src.lines().take(300).map(|l| format!("{l}\n")).collect::<String>()
            + &format!("f {}\n", (1..=256).map(|k| k.to_string()).collect::<Vec<_>>().join(" "));
        assert!(!matches!(read_obj(cut.as_bytes()), Err(ObjError::Syntax { .. })));
    }

    #[test]
    fn reads_positions_polygons_and_slashed_corners() {
        let src = "# a square and a triangle\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1.0\nvn 0 0 1\n\
                   o quad\nf 1/1/1 2/2/1 3//1 4\nf -4 -3 -1\n";
        let m = read_obj(src.as_bytes()).unwrap();
        assert_eq!(m.n_vertices(), 4);
        assert_eq!(m.triangles(), &[[0, 1, 2], [0, 2, 3], [0, 1, 3]]);
    }

    #[test]
    fn errors_name_line_and_column() {
        let err = read_obj("v 0 0 0\nv 1 x 0\n".as_bytes()).unwrap_err().to_string();
        assert_eq!(err, "2:5: expected a finite number, found \"x\"");
        let err = read_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n".as_bytes()).unwrap_err().to_string();
        assert_eq!(err, "4:7: vertex index 4 is out of range (the file has 3 vertices)");
        let err = read_obj("v 0 0 0\nf 1 -2 1\n".as_bytes()).unwrap_err().to_string();
        assert!(err.starts_with("2:5: vertex index -2"), "{err}");
        let err = read_obj("v 0 0 0\nf 1 0 1\n".as_bytes()).unwrap_err().to_string();
        assert_eq!(err, "2:5: expected a non-zero vertex index, found \"0\"");
        let err = read_obj("v 0 0\n".as_bytes()).unwrap_err().to_string();
        assert_eq!(err, "1:6: expected coordinate 3 of a vertex, found end of line");
        assert!(matches!(read_obj("v 0 0 0\n".as_bytes()), Err(ObjError::NoFaces)));
        let err = read_obj("v 0 0 0\nv 1 0 0\nf 1 2\n".as_bytes()).unwrap_err().to_string();
        assert!(err.contains("at least three corners"), "{err}");
    }
}
