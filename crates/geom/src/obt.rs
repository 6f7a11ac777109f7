//! The `.OBT` object format (Nedel 1993, Annex A-1, pp. 123–124): the UFRGS graphics group's common
//! object format. FLEX3D reads static scene objects in it and writes every output frame in it.
//!
//! ```text
//! $OBJETO <nome> <x> <y> <z> <raio>
//! $VÉRTICES <num_vert>
//! [<x> <y> <z>]*
//! $FACES <num_faces>
//! [<nv> <v1> <v2> ... <vn> <ind_tab_desc>]*
//! $DESCRIÇÃO
//! [#<n> <R> <G> <B> <coef_dif> <espec> <amb>]*
//! $END_OBJ
//! ```
//!
//! The annex gives the syntax only. What it leaves open follows the specification's reconstruction
//! (spec S2.6.3): tokens are separated by any whitespace, so line breaks carry no meaning; keywords may
//! be accented or ASCII, in UTF-8 or Latin-1 (files of the period were Latin-1); the vertex index base is
//! detected from the indices themselves; the writer uses 0-based indices and `{:.6}` reals, which never
//! use an exponent.

use std::borrow::Cow;
use std::fmt;
use std::io::{self, Read, Write};

use glam::DVec3;

use crate::{MeshError, TriangleMesh};

/// One object of an `.OBT` file, as written: header, vertex table, faces and colour table.
#[derive(Debug, Clone, PartialEq)]
pub struct ObtObject {
    /// `<nome>`: a single token (the writer replaces whitespace by `_`).
    pub name: String,
    /// Centre of the bounding sphere ("envoltória esférica").
    pub centre: DVec3,
    /// Radius of the bounding sphere.
    pub radius: f64,
    pub vertices: Vec<DVec3>,
    pub faces: Vec<ObtFace>,
    pub descriptions: Vec<ObtDescription>,
}

/// A planar face: `nv` vertex indices and a colour entry.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ObtFace {
    /// Indices into [`ObtObject::vertices`], always 0-based once read, whatever base the file used.
    pub vertices: Vec<usize>,
    /// `<ind_tab_desc>` as written: the number `n` of a `#<n>` colour entry. It is kept as is, not
    /// rebased, because the entries carry their own numbers and the annex does not say how they relate.
    pub description: usize,
}

/// A colour-table entry `#<n> <R> <G> <B> <coef_dif> <espec> <amb>`. The annex gives no ranges, so
/// values pass through unchecked (spec S2.6.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObtDescription {
    pub number: usize,
    pub rgb: [f64; 3],
    pub diffuse: f64,
    pub specular: f64,
    pub ambient: f64,
}

/// The base of the vertex indices in a file. The annex does not say (ambiguity A-10), so the reader
/// looks at the indices first: an index equal to `num_vert` can only be 1-based, an index 0 only
/// 0-based. This setting decides when the file shows neither (or, contradictorily, both).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum IndexBase {
    /// Detect; fall back to 0-based, the writer's convention and that of the `.PAR` fixed points.
    #[default]
    Auto,
    /// Detect; fall back to 0-based.
    Zero,
    /// Detect; fall back to 1-based.
    One,
}

/// Why an `.OBT` file could not be read. Positions are 1-based lines and columns, counted in
/// characters of the decoded text.
#[derive(Debug, thiserror::Error)]
pub enum ObtError {
    #[error("could not read the object: {0}")]
    Io(#[from] io::Error),
    #[error("{line}:{column}: expected {expected}, found {}", Found(found))]
    Syntax { line: usize, column: usize, expected: String, found: String },
    #[error(
        "{line}:{column}: expected a vertex index {} (the object has {n_vertices} vertices, indices read as {}), found \"{index}\"",
        index_range(*n_vertices, *one_based),
        if *one_based { "1-based" } else { "0-based" }
    )]
    IndexOutOfRange { line: usize, column: usize, index: usize, n_vertices: usize, one_based: bool },
    #[error(
        "{line}:{column}: expected a face of at least 3 vertices, found \"{n_vertices}\" (face {face}, counted from 1)"
    )]
    TooFewVertices { line: usize, column: usize, face: usize, n_vertices: usize },
}

impl ObtError {
    /// Line and column of the offending token (`None` for I/O errors).
    pub fn position(&self) -> Option<(usize, usize)> {
        match self {
            ObtError::Io(_) => None,
            ObtError::Syntax { line, column, .. }
            | ObtError::IndexOutOfRange { line, column, .. }
            | ObtError::TooFewVertices { line, column, .. } => Some((*line, *column)),
        }
    }
}

/// The `found` text of a syntax error, quoted unless it is the end of the file.
struct Found<'a>(&'a str);

impl fmt::Display for Found<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0 == END_OF_FILE { f.write_str(END_OF_FILE) } else { write!(f, "\"{}\"", self.0) }
    }
}

const END_OF_FILE: &str = "end of file";
const DESCRIPTION_OR_END: &str = "a colour entry `#<n>` or `$END_OBJ`";

fn index_range(n_vertices: usize, one_based: bool) -> String {
    if one_based { format!("in 1..={n_vertices}") } else { format!("in 0..{n_vertices}") }
}

impl ObtObject {
    /// An output frame of a surface (spec S2.6.3): centre = mean of the positions, radius = largest
    /// distance from it, every triangle written `3 a b c 1`, one grey colour entry
    /// `#1 0.8 0.8 0.8 0.7 0.3 0.2` (an anima choice; the thesis does not give FLEX3D's).
    pub fn from_surface(name: impl Into<String>, positions: &[DVec3], triangles: &[[u32; 3]]) -> ObtObject {
        let centre = if positions.is_empty() {
            DVec3::ZERO
        } else {
            positions.iter().copied().sum::<DVec3>() / positions.len() as f64
        };
        let radius = positions.iter().map(|p| p.distance(centre)).fold(0.0, f64::max);
        ObtObject {
            name: name.into(),
            centre,
            radius,
            vertices: positions.to_vec(),
            faces: triangles
                .iter()
                .map(|t| ObtFace { vertices: t.iter().map(|&v| v as usize).collect(), description: 1 })
                .collect(),
            descriptions: vec![ObtDescription {
                number: 1,
                rgb: [0.8, 0.8, 0.8],
                diffuse: 0.7,
                specular: 0.3,
                ambient: 0.2,
            }],
        }
    }

    /// The object as triangles, which FLEX3D's collision detection needs (§5.3 p. 108). A face of
    /// `nv > 3` vertices becomes the fan (v1, vk, vk+1), k = 2..nv−1 (spec S2.5, an extension).
    pub fn to_mesh(&self) -> Result<TriangleMesh, MeshError> {
        // An index that does not fit u32 cannot name a vertex; u32::MAX makes the mesh refuse it.
        let idx = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
        let triangles = self
            .faces
            .iter()
            .flat_map(|f| f.vertices.windows(2).skip(1).map(|w| [idx(f.vertices[0]), idx(w[0]), idx(w[1])]))
            .collect();
        TriangleMesh::new(self.vertices.clone(), triangles)
    }
}

/// Reads one object. The bytes are decoded as UTF-8, or as Latin-1 when they are not valid UTF-8.
/// `base` decides the vertex index base when the indices do not reveal it (see [`IndexBase`]).
pub fn read_obt(mut r: impl Read, base: IndexBase) -> Result<ObtObject, ObtError> {
    let mut bytes = Vec::new();
    r.read_to_end(&mut bytes)?;
    let text = decode(&bytes);
    Reader::new(&text).object(base)
}

/// Writes one object as spec S2.6.3 describes: accented keywords in UTF-8, reals as `{:.6}`, 0-based
/// vertex indices, colour entries as `#<n>`.
pub fn write_obt(mut w: impl Write, obj: &ObtObject) -> io::Result<()> {
    // The format has no way to say "not a number": a frame that is not finite is not written.
    if !(obj.centre.is_finite() && obj.radius.is_finite() && obj.vertices.iter().all(|v| v.is_finite())) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!("object `{}` has non-finite coordinates", obj.name),
        ));
    }
    let name: String = obj.name.chars().map(|c| if c.is_whitespace() { '_' } else { c }).collect();
    let name = if name.is_empty() { "objeto" } else { &name };
    let c = obj.centre;
    writeln!(w, "$OBJETO {name} {:.6} {:.6} {:.6} {:.6}", c.x, c.y, c.z, obj.radius)?;
    writeln!(w, "$VÉRTICES {}", obj.vertices.len())?;
    for v in &obj.vertices {
        writeln!(w, "{:.6} {:.6} {:.6}", v.x, v.y, v.z)?;
    }
    writeln!(w, "$FACES {}", obj.faces.len())?;
    for f in &obj.faces {
        write!(w, "{}", f.vertices.len())?;
        for v in &f.vertices {
            write!(w, " {v}")?;
        }
        writeln!(w, " {}", f.description)?;
    }
    writeln!(w, "$DESCRIÇÃO")?;
    for d in &obj.descriptions {
        let [r, g, b] = d.rgb;
        writeln!(
            w,
            "#{} {r:.6} {g:.6} {b:.6} {:.6} {:.6} {:.6}",
            d.number, d.diffuse, d.specular, d.ambient
        )?;
    }
    writeln!(w, "$END_OBJ")?;
    w.flush()
}

/// UTF-8 if valid, else Latin-1, whose bytes are the first 256 code points.
fn decode(bytes: &[u8]) -> Cow<'_, str> {
    match std::str::from_utf8(bytes) {
        Ok(s) => Cow::Borrowed(s.strip_prefix('\u{feff}').unwrap_or(s)),
        Err(_) => Cow::Owned(bytes.iter().map(|&b| char::from(b)).collect()),
    }
}

/// The keywords, compared after upper-casing and folding the Portuguese accents to ASCII.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Keyword {
    Objeto,
    Vertices,
    Faces,
    Descricao,
    EndObj,
}

impl Keyword {
    fn spelling(self) -> &'static str {
        match self {
            Keyword::Objeto => "`$OBJETO`",
            Keyword::Vertices => "`$VÉRTICES`",
            Keyword::Faces => "`$FACES`",
            Keyword::Descricao => "`$DESCRIÇÃO`",
            Keyword::EndObj => "`$END_OBJ`",
        }
    }

    fn of(text: &str) -> Option<Keyword> {
        let folded: String = text
            .chars()
            .flat_map(char::to_uppercase)
            .map(|c| match c {
                'Á' | 'À' | 'Â' | 'Ã' => 'A',
                'É' | 'Ê' => 'E',
                'Í' => 'I',
                'Ó' | 'Ô' | 'Õ' => 'O',
                'Ú' => 'U',
                'Ç' => 'C',
                c => c,
            })
            .collect();
        Some(match folded.as_str() {
            "$OBJETO" => Keyword::Objeto,
            "$VERTICES" => Keyword::Vertices,
            "$FACES" => Keyword::Faces,
            "$DESCRICAO" => Keyword::Descricao,
            "$END_OBJ" => Keyword::EndObj,
            _ => return None,
        })
    }
}

#[derive(Debug, Clone, Copy)]
struct Token<'a> {
    text: &'a str,
    line: usize,
    column: usize,
}

/// A whitespace tokenizer with a cursor. The end-of-file position is just after the last token.
struct Reader<'a> {
    tokens: Vec<Token<'a>>,
    pos: usize,
    eof: (usize, usize),
}

impl<'a> Reader<'a> {
    fn new(text: &'a str) -> Self {
        let mut tokens = Vec::new();
        let (mut line, mut column) = (1, 1);
        let mut start: Option<(usize, usize, usize)> = None;
        let mut eof = (1, 1);
        for (byte, c) in text.char_indices() {
            if c.is_whitespace() {
                if let Some((b, l, col)) = start.take() {
                    tokens.push(Token { text: &text[b..byte], line: l, column: col });
                    eof = (line, column);
                }
            } else if start.is_none() {
                start = Some((byte, line, column));
            }
            if c == '\n' {
                line += 1;
                column = 1;
            } else {
                column += 1;
            }
        }
        if let Some((b, l, col)) = start {
            tokens.push(Token { text: &text[b..], line: l, column: col });
            eof = (line, column);
        }
        Reader { tokens, pos: 0, eof }
    }

    fn peek(&self) -> Option<Token<'a>> {
        self.tokens.get(self.pos).copied()
    }

    fn error(&self, at: Option<Token<'a>>, expected: impl Into<String>) -> ObtError {
        let (line, column, found) = match at {
            Some(t) => (t.line, t.column, t.text.to_owned()),
            None => (self.eof.0, self.eof.1, END_OF_FILE.to_owned()),
        };
        ObtError::Syntax { line, column, expected: expected.into(), found }
    }

    fn next(&mut self, expected: &str) -> Result<Token<'a>, ObtError> {
        let t = self.peek().ok_or_else(|| self.error(None, expected))?;
        self.pos += 1;
        Ok(t)
    }

    fn keyword(&mut self, kw: Keyword) -> Result<(), ObtError> {
        let t = self.next(kw.spelling())?;
        if Keyword::of(t.text) == Some(kw) { Ok(()) } else { Err(self.error(Some(t), kw.spelling())) }
    }

    fn real(&mut self, what: &str) -> Result<f64, ObtError> {
        let expected = format!("a number ({what})");
        let t = self.next(&expected)?;
        match t.text.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(self.error(Some(t), expected)),
        }
    }

    fn vec3(&mut self, what: &str) -> Result<DVec3, ObtError> {
        Ok(DVec3::new(
            self.real(&format!("x of {what}"))?,
            self.real(&format!("y of {what}"))?,
            self.real(&format!("z of {what}"))?,
        ))
    }

    fn count(&mut self, what: &str) -> Result<(usize, Token<'a>), ObtError> {
        let expected = format!("a whole number ({what})");
        let t = self.next(&expected)?;
        match t.text.parse::<usize>() {
            Ok(n) if t.text.bytes().all(|b| b.is_ascii_digit()) => Ok((n, t)),
            _ => Err(self.error(Some(t), expected)),
        }
    }

    fn object(mut self, base: IndexBase) -> Result<ObtObject, ObtError> {
        self.keyword(Keyword::Objeto)?;
        let name = self.next("an object name")?;
        if Keyword::of(name.text).is_some() {
            return Err(self.error(Some(name), "an object name"));
        }
        let centre = self.vec3("the bounding-sphere centre")?;
        let radius = self.real("the bounding-sphere radius")?;

        self.keyword(Keyword::Vertices)?;
        let (n_vertices, _) = self.count("the number of vertices")?;
        let vertices = (0..n_vertices)
            .map(|k| self.vec3(&format!("vertex {} of {n_vertices}", k + 1)))
            .collect::<Result<Vec<_>, _>>()?;

        self.keyword(Keyword::Faces)?;
        let (n_faces, _) = self.count("the number of faces")?;
        // The count is the file's promise; the faces themselves decide how much is stored.
        let mut raw_faces: Vec<(Vec<(usize, Token<'a>)>, usize)> = Vec::with_capacity(n_faces.min(1024));
        for face in 1..=n_faces {
            let (nv, nv_tok) = self.count(&format!("the vertex count of face {face} of {n_faces}"))?;
            if nv < 3 {
                let (line, column) = (nv_tok.line, nv_tok.column);
                return Err(ObtError::TooFewVertices { line, column, face, n_vertices: nv });
            }
            let indices = (1..=nv)
                .map(|k| self.count(&format!("vertex {k} of {nv} of face {face}")))
                .collect::<Result<Vec<_>, _>>()?;
            let (description, _) = self.count(&format!("the colour entry of face {face}"))?;
            raw_faces.push((indices, description));
        }

        self.keyword(Keyword::Descricao)?;
        let mut descriptions = Vec::new();
        loop {
            match self.peek() {
                None => return Err(self.error(None, DESCRIPTION_OR_END)),
                Some(t) if Keyword::of(t.text) == Some(Keyword::EndObj) => break self.pos += 1,
                Some(_) => descriptions.push(self.description()?),
            }
        }
        if let Some(t) = self.peek() {
            return Err(self.error(Some(t), "end of file after `$END_OBJ`"));
        }

        let one_based = detect_one_based(&raw_faces, n_vertices, base);
        let faces = raw_faces
            .into_iter()
            .map(|(indices, description)| {
                let vertices = indices
                    .into_iter()
                    .map(|(index, t)| {
                        let v = if one_based { index.checked_sub(1) } else { Some(index) };
                        v.filter(|&v| v < n_vertices).ok_or(ObtError::IndexOutOfRange {
                            line: t.line,
                            column: t.column,
                            index,
                            n_vertices,
                            one_based,
                        })
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                Ok(ObtFace { vertices, description })
            })
            .collect::<Result<Vec<_>, ObtError>>()?;
        Ok(ObtObject { name: name.text.to_owned(), centre, radius, vertices, faces, descriptions })
    }

    /// `#<n> R G B dif espec amb`; `# <n>` with a space is accepted too.
    fn description(&mut self) -> Result<ObtDescription, ObtError> {
        const EXPECTED: &str = DESCRIPTION_OR_END;
        let t = self.next(EXPECTED)?;
        let Some(digits) = t.text.strip_prefix('#') else {
            return Err(self.error(Some(t), EXPECTED));
        };
        let number = if digits.is_empty() {
            self.count("the colour entry number after `#`")?.0
        } else if digits.bytes().all(|b| b.is_ascii_digit()) {
            digits.parse().map_err(|_| self.error(Some(t), EXPECTED))?
        } else {
            return Err(self.error(Some(t), EXPECTED));
        };
        let what = |c: &str| format!("{c} of colour entry #{number}");
        Ok(ObtDescription {
            number,
            rgb: [self.real(&what("R"))?, self.real(&what("G"))?, self.real(&what("B"))?],
            diffuse: self.real(&what("the diffuse coefficient"))?,
            specular: self.real(&what("the specular coefficient"))?,
            ambient: self.real(&what("the ambient coefficient"))?,
        })
    }
}

/// Spec S2.6.3: an index equal to `num_vert` means 1-based, an index 0 means 0-based; with no
/// evidence, or contradictory evidence, the configured base decides (and the range check then names
/// the index that does not fit).
fn detect_one_based(faces: &[(Vec<(usize, Token<'_>)>, usize)], n_vertices: usize, base: IndexBase) -> bool {
    let indices = || faces.iter().flat_map(|(ix, _)| ix.iter().map(|&(i, _)| i));
    let has_zero = indices().any(|i| i == 0);
    let has_n = indices().any(|i| i == n_vertices);
    match (has_zero, has_n) {
        (true, false) => false,
        (false, true) => true,
        _ => base == IndexBase::One,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The illustrative 2×2 frame of spec S2.6.3.
    const PANO: &str = "$OBJETO PANO 0.0 40.0 0.0 1.414214
$VÉRTICES 4
-1.0 41.0 0.0
1.0 41.0 0.0
-1.0 39.0 0.0
1.0 39.0 0.0
$FACES 2
3 0 2 3 1
3 0 3 1 1
$DESCRIÇÃO
#1 0.8 0.8 0.8 0.7 0.3 0.2
$END_OBJ
";

    fn read(text: &str) -> Result<ObtObject, ObtError> {
        read_obt(text.as_bytes(), IndexBase::Auto)
    }

    fn syntax(err: ObtError) -> (usize, usize, String, String) {
        match err {
            ObtError::Syntax { line, column, expected, found } => (line, column, expected, found),
            other => panic!("expected a syntax error, got {other}"),
        }
    }

    #[test]
    #[expect(clippy::approx_constant, reason = "1.414214 is √2 as the file writes it, to 6 decimals")]
    fn reads_the_pano_example() {
        let o = read(PANO).unwrap();
        assert_eq!(o.name, "PANO");
        assert_eq!(o.centre, DVec3::new(0.0, 40.0, 0.0));
        assert_eq!(o.radius, 1.414214);
        assert_eq!(o.vertices.len(), 4);
        assert_eq!(o.vertices[2], DVec3::new(-1.0, 39.0, 0.0));
        assert_eq!(o.faces[0], ObtFace { vertices: vec![0, 2, 3], description: 1 });
        assert_eq!(o.faces[1], ObtFace { vertices: vec![0, 3, 1], description: 1 });
        assert_eq!(
            o.descriptions,
            vec![ObtDescription { number: 1, rgb: [0.8; 3], diffuse: 0.7, specular: 0.3, ambient: 0.2 }]
        );
        let mesh = o.to_mesh().unwrap();
        assert_eq!(mesh.triangles(), &[[0, 2, 3], [0, 3, 1]]);
    }

    #[test]
    fn line_breaks_carry_no_meaning() {
        let flat = PANO.split_whitespace().collect::<Vec<_>>().join(" ");
        assert_eq!(read(&flat).unwrap(), read(PANO).unwrap());
    }

    #[test]
    #[expect(clippy::approx_constant, reason = "1.414214 is √2 as the file writes it, to 6 decimals")]
    fn write_then_read_round_trips() {
        let positions = [
            DVec3::new(-1.0, 41.0, 0.0),
            DVec3::new(1.0, 41.0, 0.0),
            DVec3::new(-1.0, 39.0, 0.0),
            DVec3::new(1.0, 39.0, 0.0),
        ];
        let obj = ObtObject::from_surface("PANO", &positions, &[[0, 2, 3], [0, 3, 1]]);
        assert_eq!(obj.centre, DVec3::new(0.0, 40.0, 0.0));
        assert!((obj.radius - 2f64.sqrt()).abs() < 1e-15);
        let mut out = Vec::new();
        write_obt(&mut out, &obj).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.starts_with("$OBJETO PANO 0.000000 40.000000 0.000000 1.414214\n$VÉRTICES 4\n"));
        assert!(text.contains("\n3 0 2 3 1\n") && text.contains("\n$DESCRIÇÃO\n#1 0.800000 "));
        let back = read(&text).unwrap();
        // {:.6} rounds the radius; everything else here has at most 6 decimals.
        assert_eq!(back.radius, 1.414214);
        assert_eq!(ObtObject { radius: obj.radius, ..back }, obj);
    }

    #[test]
    fn detects_one_based_indices() {
        let one = PANO.replace("3 0 2 3 1\n3 0 3 1 1", "3 1 3 4 1\n3 1 4 2 1");
        let o = read(&one).unwrap();
        assert_eq!(o.faces[0].vertices, vec![0, 2, 3]);
        assert_eq!(o.faces[1].vertices, vec![0, 3, 1]);
    }

    #[test]
    fn configured_base_decides_without_evidence() {
        // Indices 1..3 of 4 vertices: neither 0 nor 4 appears.
        let text = PANO.replace("3 0 2 3 1\n3 0 3 1 1", "3 1 2 3 1\n3 1 3 2 1");
        assert_eq!(read_obt(text.as_bytes(), IndexBase::Auto).unwrap().faces[0].vertices, vec![1, 2, 3]);
        assert_eq!(read_obt(text.as_bytes(), IndexBase::Zero).unwrap().faces[0].vertices, vec![1, 2, 3]);
        assert_eq!(read_obt(text.as_bytes(), IndexBase::One).unwrap().faces[0].vertices, vec![0, 1, 2]);
    }

    #[test]
    fn reads_latin1_and_ascii_keywords() {
        let latin1: Vec<u8> = PANO.chars().map(|c| u8::try_from(u32::from(c)).unwrap()).collect();
        assert!(std::str::from_utf8(&latin1).is_err(), "the test input must not be UTF-8");
        assert_eq!(read_obt(&latin1[..], IndexBase::Auto).unwrap(), read(PANO).unwrap());
        let ascii = PANO.replace("$VÉRTICES", "$vertices").replace("$DESCRIÇÃO", "$DESCRICAO");
        assert_eq!(read(&ascii).unwrap(), read(PANO).unwrap());
    }

    #[test]
    fn fans_faces_with_more_than_three_vertices() {
        let quad = PANO.replace("$FACES 2\n3 0 2 3 1\n3 0 3 1 1", "$FACES 1\n4 0 2 3 1 1");
        let mesh = read(&quad).unwrap().to_mesh().unwrap();
        assert_eq!(mesh.triangles(), &[[0, 2, 3], [0, 3, 1]]);
    }

    #[test]
    fn syntax_errors_name_line_column_expected_and_found() {
        let (line, column, expected, found) =
            syntax(read(&PANO.replace("-1.0 39.0", "-1.0 abc")).unwrap_err());
        assert_eq!((line, column, found.as_str()), (5, 6, "abc"));
        assert_eq!(expected, "a number (y of vertex 3 of 4)");

        let err = read(&PANO.replace("$FACES", "$FACE")).unwrap_err();
        assert_eq!(err.to_string(), "7:1: expected `$FACES`, found \"$FACE\"");

        let err = read(&PANO.replace("$END_OBJ\n", "")).unwrap_err();
        assert_eq!(err.to_string(), "11:27: expected a colour entry `#<n>` or `$END_OBJ`, found end of file");
    }

    #[test]
    fn out_of_range_index_and_short_face_are_errors() {
        let err = read(&PANO.replace("3 0 3 1 1", "3 0 3 7 1")).unwrap_err();
        assert!(matches!(err, ObtError::IndexOutOfRange { line: 9, column: 7, index: 7, n_vertices: 4, .. }));
        assert_eq!(
            err.to_string(),
            "9:7: expected a vertex index in 0..4 (the object has 4 vertices, indices read as 0-based), found \"7\""
        );
        let err = read(&PANO.replace("3 0 3 1 1", "2 0 3 1")).unwrap_err();
        assert!(matches!(err, ObtError::TooFewVertices { line: 9, column: 1, face: 2, n_vertices: 2 }));
        // 0 and num_vert in one file: the default base (0-based) decides and 4 is out of range.
        let err = read(&PANO.replace("3 0 3 1 1", "3 0 3 4 1")).unwrap_err();
        assert_eq!(err.position(), Some((9, 7)));
    }
}
