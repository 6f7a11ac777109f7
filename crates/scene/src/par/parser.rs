//! Recursive descent over the tokens, one method per rule of the grammar in the module docs. Every
//! error names the token where the script stops making sense, or the end of the file.

use anima_cloth::flex3d::Translation;
use anima_geom::DVec3;

use super::lexer::{Keyword, Token, TokenKind, Tokens};
use super::{Curvature, ParScript, ParSurface};
use crate::END_OF_FILE;
use crate::ParseError;

type Result<T> = std::result::Result<T, ParseError>;

pub(super) fn script(tokens: &Tokens) -> Result<ParScript> {
    Parser { tokens: &tokens.tokens, pos: 0, eof: (tokens.eof_line, tokens.eof_column), particles: 0 }
        .script()
}

/// Room reserved for a declared count before the items are read: a count is a promise the text may
/// not keep, so it never sizes an allocation by itself.
const RESERVE: usize = 64;

/// What a `RESTRIÇÕES … FIM_RESTRIÇÕES` block says.
struct Restrictions {
    fixed: Vec<(usize, usize)>,
    translations: Vec<Translation>,
}

struct Parser<'t> {
    tokens: &'t [Token],
    pos: usize,
    eof: (usize, usize),
    /// Particles of the surfaces read so far, against [`crate::limits::MAX_PARTICLES`].
    particles: usize,
}

/// A decimal real as the thesis writes them (`-0.39`, `10.0`, `0`, `25`). An exponent is accepted;
/// `inf`, `NaN` and hexadecimal, which Rust's float parser would take, are not.
fn real(text: &str) -> Option<f64> {
    let decimal = text.bytes().all(|b| b.is_ascii_digit() || matches!(b, b'+' | b'-' | b'.' | b'e' | b'E'))
        && text.bytes().any(|b| b.is_ascii_digit());
    text.parse::<f64>().ok().filter(|x| decimal && x.is_finite())
}

/// A whole number, possibly signed (so `-1` is reported as out of range rather than as not a number).
fn integer(text: &str) -> Option<i64> {
    text.parse().ok()
}

impl<'t> Parser<'t> {
    fn peek(&self) -> Option<&'t Token> {
        self.tokens.get(self.pos)
    }

    fn bump(&mut self) -> Option<&'t Token> {
        let t = self.peek();
        self.pos += usize::from(t.is_some());
        t
    }

    fn error(&self, at: Option<&Token>, expected: impl Into<String>) -> ParseError {
        match at {
            Some(t) => ParseError::new(t.line, t.column, expected, t.text.clone()),
            None => ParseError::new(self.eof.0, self.eof.1, expected, END_OF_FILE),
        }
    }

    fn error_here(&self, expected: impl Into<String>) -> ParseError {
        self.error(self.peek(), expected)
    }

    fn at_keyword(&self, kw: Keyword) -> bool {
        self.peek().and_then(Token::keyword) == Some(kw)
    }

    fn at_kind(&self, kind: TokenKind) -> bool {
        self.peek().is_some_and(|t| t.kind == kind)
    }

    /// A plain word: not a keyword and not `(`, `)`, `=`.
    fn at_name(&self) -> bool {
        self.peek().is_some_and(|t| t.kind == TokenKind::Word && t.keyword().is_none())
    }

    fn at_number(&self) -> bool {
        self.peek().is_some_and(|t| t.kind == TokenKind::Word && real(&t.text).is_some())
    }

    fn keyword(&mut self, kw: Keyword) -> Result<()> {
        self.keyword_or(kw, kw.to_string())
    }

    fn keyword_or(&mut self, kw: Keyword, expected: impl Into<String>) -> Result<()> {
        if self.at_keyword(kw) {
            self.pos += 1;
            Ok(())
        } else {
            Err(self.error_here(expected))
        }
    }

    /// `KEYWORD =?`: the scripts write `=` before some values and not others (spec S5.4 item 1).
    fn setting(&mut self, kw: Keyword) -> Result<()> {
        self.keyword(kw)?;
        if self.at_kind(TokenKind::Equals) {
            self.pos += 1;
        }
        Ok(())
    }

    fn number(&mut self, what: &str) -> Result<(f64, &'t Token)> {
        let expected = || format!("a number for {what}");
        let t = self.peek().ok_or_else(|| self.error_here(expected()))?;
        match real(&t.text) {
            Some(x) if t.kind == TokenKind::Word => {
                self.pos += 1;
                Ok((x, t))
            }
            _ => Err(self.error(Some(t), expected())),
        }
    }

    /// `KEYWORD =? num` with num > 0 (spec S5.2.2 validation: times, spacing and mass).
    fn positive_setting(&mut self, kw: Keyword) -> Result<f64> {
        self.setting(kw)?;
        let (x, t) = self.number(&kw.to_string())?;
        if x > 0.0 { Ok(x) } else { Err(self.error(Some(t), format!("a positive number for {kw}"))) }
    }

    /// `KEYWORD =? num` with num ≥ 0 (a friction coefficient).
    fn non_negative_setting(&mut self, kw: Keyword) -> Result<f64> {
        self.setting(kw)?;
        let (x, t) = self.number(&kw.to_string())?;
        if x >= 0.0 { Ok(x) } else { Err(self.error(Some(t), format!("a number ≥ 0 for {kw}"))) }
    }

    fn number_setting(&mut self, kw: Keyword) -> Result<f64> {
        self.setting(kw)?;
        Ok(self.number(&kw.to_string())?.0)
    }

    /// A whole number `≥ min`, described by `expected` in the error.
    fn whole(&mut self, min: i64, expected: impl Into<String>) -> Result<usize> {
        let t = self.peek();
        match t.filter(|t| t.kind == TokenKind::Word).and_then(|t| integer(&t.text)) {
            Some(n) if n >= min => {
                self.pos += 1;
                Ok(n as usize)
            }
            _ => Err(self.error(t, expected)),
        }
    }

    /// An index `0 ≤ k < limit`.
    fn index(&mut self, limit: usize, expected: impl Into<String>) -> Result<usize> {
        let t = self.peek();
        match t.filter(|t| t.kind == TokenKind::Word).and_then(|t| integer(&t.text)) {
            Some(k) if k >= 0 && (k as u64) < limit as u64 => {
                self.pos += 1;
                Ok(k as usize)
            }
            _ => Err(self.error(t, expected)),
        }
    }

    /// An optional `(`; the matching [`Parser::close`] then requires the `)`.
    fn open(&mut self) -> bool {
        let opened = self.at_kind(TokenKind::LParen);
        self.pos += usize::from(opened);
        opened
    }

    fn close(&mut self, opened: bool, what: Keyword) -> Result<()> {
        if !opened {
            return Ok(());
        }
        if self.at_kind(TokenKind::RParen) {
            self.pos += 1;
            Ok(())
        } else {
            Err(self.error_here(format!("`)` closing {what}")))
        }
    }

    /// `(? x y z )?`; returns the vector and the index of the token of its first component.
    fn vec3(&mut self, what: Keyword) -> Result<(DVec3, usize)> {
        let opened = self.open();
        let first = self.pos;
        let (x, _) = self.number(&format!("x of {what}"))?;
        let (y, _) = self.number(&format!("y of {what}"))?;
        let (z, _) = self.number(&format!("z of {what}"))?;
        self.close(opened, what)?;
        Ok((DVec3::new(x, y, z), first))
    }

    fn vec3_setting(&mut self, kw: Keyword) -> Result<DVec3> {
        self.setting(kw)?;
        Ok(self.vec3(kw)?.0)
    }

    fn script(&mut self) -> Result<ParScript> {
        let duration_s = self.positive_setting(Keyword::Duracao)?;
        let frame_rate_hz = self.positive_setting(Keyword::QuadrosSeg)?;
        let dt_s = self.positive_setting(Keyword::DeltaT)?;
        if let Some(why) = crate::limits::run_length_problem(duration_s, dt_s, Some(frame_rate_hz)) {
            // Point at the step's value, the number that sets how many steps there are.
            return Err(self.error(self.tokens.get(self.pos - 1), why));
        }
        let external_force_n = self.vec3_setting(Keyword::ForcaExterna)?;
        let friction = self.non_negative_setting(Keyword::Atrito)?;

        self.setting(Keyword::ObjetosNaCena)?;
        let n_objects = self.whole(0, format!("a whole number for {}", Keyword::ObjetosNaCena))?;
        let mut objects = Vec::with_capacity(n_objects.min(RESERVE));
        for k in 1..=n_objects {
            if !self.at_name() {
                return Err(self.error_here(format!(
                    "an .OBT file name ({k} of {n_objects} declared by {})",
                    Keyword::ObjetosNaCena
                )));
            }
            objects.push(self.bump().map(|t| t.text.clone()).unwrap_or_default());
        }

        let gravity_m_s2 = if self.at_keyword(Keyword::Gravidade) {
            Some(self.vec3_setting(Keyword::Gravidade)?)
        } else {
            None
        };

        let expected = if self.at_name() && self.peek().is_some_and(|t| t.text.contains('.')) {
            // A file name where NUM_SUPERFÍCIES goes is most likely one name too many.
            format!(
                "{} ({} = {n_objects} declares {n_objects} file names)",
                Keyword::NumSuperficies,
                Keyword::ObjetosNaCena
            )
        } else if gravity_m_s2.is_none() {
            format!("{} or {}", Keyword::Gravidade, Keyword::NumSuperficies)
        } else {
            Keyword::NumSuperficies.to_string()
        };
        self.keyword_or(Keyword::NumSuperficies, expected)?;
        if self.at_kind(TokenKind::Equals) {
            self.pos += 1;
        }
        let n_surfaces = self.whole(1, format!("a whole number ≥ 1 for {}", Keyword::NumSuperficies))?;

        let mut surfaces: Vec<ParSurface> = Vec::with_capacity(n_surfaces.min(RESERVE));
        for k in 1..=n_surfaces {
            let expected = format!(
                "{} (surface {k} of {n_surfaces} declared by {})",
                Keyword::Superficie,
                Keyword::NumSuperficies
            );
            self.keyword_or(Keyword::Superficie, expected)?;
            let name_token = self.peek();
            let surface = self.surface()?;
            // A surface's name names its frame files: it must be plain, and no other surface's.
            if let Some(name) = &surface.name {
                let at = name_token.filter(|t| &t.text == name);
                if let Some(why) = anima_format::not_a_plain_name(name) {
                    return Err(self.error(at, why));
                }
                if let Some(first) = surfaces.iter().position(|s| s.name.as_ref() == Some(name)) {
                    return Err(self.error(
                        at,
                        format!("a name no other surface has (surface {} is `{name}` too)", first + 1),
                    ));
                }
            }
            surfaces.push(surface);
        }
        if let Some(t) = self.peek() {
            let expected = if t.keyword() == Some(Keyword::Superficie) {
                format!("end of file ({} = {n_surfaces})", Keyword::NumSuperficies)
            } else {
                "end of file".to_owned()
            };
            return Err(self.error(Some(t), expected));
        }

        Ok(ParScript {
            duration_s,
            frame_rate_hz,
            dt_s,
            external_force_n,
            friction,
            objects,
            gravity_m_s2,
            surfaces,
        })
    }

    /// The block after `SUPERFÍCIE`, up to and including `FIM_SUPERFÍCIE`.
    fn surface(&mut self) -> Result<ParSurface> {
        let name = if self.at_name() { self.bump().map(|t| t.text.clone()) } else { None };

        self.setting(Keyword::Malha)?;
        let opened = self.open();
        // A 1-wide mesh has no triangles and no diagonal springs (spec S2.1).
        let rows_token = self.peek();
        let rows = self.whole(2, format!("a whole number of rows ≥ 2 for {}", Keyword::Malha))?;
        let cols = self.whole(2, format!("a whole number of columns ≥ 2 for {}", Keyword::Malha))?;
        self.close(opened, Keyword::Malha)?;
        let max = crate::limits::MAX_PARTICLES;
        match rows.checked_mul(cols).and_then(|n| n.checked_add(self.particles)).filter(|&n| n <= max) {
            Some(n) => self.particles = n,
            None => {
                return Err(self.error(
                    rows_token,
                    format!("a mesh whose particles, with the other surfaces', number at most {max} ({rows} × {cols} here)"),
                ));
            }
        }

        let spacing_m = self.positive_setting(Keyword::Densidade)?;
        let centre_m = self.vec3_setting(Keyword::PosicNoSru)?;

        self.setting(Keyword::VetorNormal)?;
        let (normal, first) = self.vec3(Keyword::VetorNormal)?;
        if normal == DVec3::ZERO {
            // Point at the first component; show all three, as written.
            let components = &self.tokens[first..first + 3];
            let mut e = self.error(Some(&components[0]), format!("a non-zero {}", Keyword::VetorNormal));
            e.found = components.iter().map(|t| t.text.as_str()).collect::<Vec<_>>().join(" ");
            return Err(e);
        }

        let particle_mass_kg = self.positive_setting(Keyword::Massa)?;
        self.setting(Keyword::ConstElasticidade)?;
        let (k, first) = self.vec3(Keyword::ConstElasticidade)?;
        if let Some(c) = (0..3).find(|&c| k[c] < 0.0) {
            return Err(self.error(
                self.tokens.get(first + c),
                format!("a stiffness ≥ 0 for {}", Keyword::ConstElasticidade),
            ));
        }
        let stiffness_n_m = k.to_array();
        let curvature = self.curvature()?;
        let Restrictions { fixed, translations } = self.restrictions(rows, cols)?;
        self.keyword(Keyword::FimSuperficie)?;

        Ok(ParSurface {
            name,
            rows,
            cols,
            spacing_m,
            centre_m,
            normal,
            particle_mass_kg,
            stiffness_n_m,
            curvature,
            fixed,
            translations,
        })
    }

    /// `CONST_CURVATURA =? (num | vec3)`.
    fn curvature(&mut self) -> Result<Curvature> {
        let kw = Keyword::ConstCurvatura;
        self.setting(kw)?;
        let opened = self.open();
        let non_negative = |p: &mut Self, what: String| -> Result<f64> {
            let (k, t) = p.number(&what)?;
            if k >= 0.0 { Ok(k) } else { Err(p.error(Some(t), format!("a constant ≥ 0 for {kw}"))) }
        };
        let k1 = non_negative(self, kw.to_string())?;
        let curvature = if self.at_number() {
            let k2 = non_negative(self, kw.to_string())?;
            let k3 = non_negative(self, format!("{kw} (it takes 1 value or 3)"))?;
            Curvature::PerPair([k1, k2, k3])
        } else {
            Curvature::One(k1)
        };
        self.close(opened, kw)?;
        Ok(curvature)
    }

    /// `RESTRIÇÕES PONTOS_FIXOS =? n (i j){n} translation* FIM_RESTRIÇÕES`.
    fn restrictions(&mut self, rows: usize, cols: usize) -> Result<Restrictions> {
        self.keyword(Keyword::Restricoes)?;
        self.setting(Keyword::PontosFixos)?;
        let n_token = self.peek();
        let n_fixed = self.whole(0, format!("a whole number for {}", Keyword::PontosFixos))?;
        if n_fixed > rows * cols {
            return Err(self.error(
                n_token,
                format!(
                    "at most {} fixed points for {} (the mesh has {rows} × {cols} particles)",
                    rows * cols,
                    Keyword::PontosFixos
                ),
            ));
        }
        let mut fixed = Vec::with_capacity(n_fixed.min(RESERVE));
        for p in 1..=n_fixed {
            let i = self.index(rows, format!("a row index 0 ≤ i < {rows} (fixed point {p} of {n_fixed})"))?;
            let j =
                self.index(cols, format!("a column index 0 ≤ j < {cols} (fixed point {p} of {n_fixed})"))?;
            fixed.push((i, j));
        }

        let mut translations = Vec::new();
        while self.at_keyword(Keyword::Translacao) {
            let per_frame_m = self.vec3_setting(Keyword::Translacao)?;
            let start_s = self.number_setting(Keyword::IniTransl)?;
            let end_s = self.number_setting(Keyword::FimTransl)?;
            translations.push(Translation { per_frame_m, start_s, end_s });
        }

        let expected = if self.peek().is_some_and(|t| integer(&t.text).is_some()) {
            format!(
                "{} or {} ({} = {n_fixed} declares {n_fixed} pairs)",
                Keyword::Translacao,
                Keyword::FimRestricoes,
                Keyword::PontosFixos
            )
        } else {
            format!("{} or {}", Keyword::Translacao, Keyword::FimRestricoes)
        };
        self.keyword_or(Keyword::FimRestricoes, expected)?;
        Ok(Restrictions { fixed, translations })
    }
}
