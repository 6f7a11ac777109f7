//! The FLEX3D animation language, `.PAR` (Nedel 1993 §5.2, pp. 103–108).
//!
//! The thesis calls its grammar informal (§5.2.1), and its own example scripts depart from it: `=` before
//! vectors, three values for `CONST_CURVATURA`, `RESTRICÇÕES` beside `RESTRIÇÕES`, an unnamed surface,
//! two surfaces and two translations per surface (spec S5.4). This module reads the normalised grammar
//! of spec S5.2.2, which accepts every script of the thesis unchanged and nothing much wider:
//!
//! ```text
//! script      = header surface{NUM_SUPERFÍCIES}
//! header      = DURAÇÃO =? num  QUADROS_SEG =? num  DELTA_t =? num  FORÇA_EXTERNA =? vec3  ATRITO =? num
//!               OBJETOS_NA_CENA =? int filename{int}  [GRAVIDADE =? vec3]  NUM_SUPERFÍCIES =? int
//! surface     = SUPERFÍCIE name?  MALHA =? (? int int )?  DENSIDADE =? num  POSIC_NO_SRU =? vec3
//!               VETOR_NORMAL =? vec3  MASSA =? num  CONST_ELASTICIDADE =? vec3
//!               CONST_CURVATURA =? (num | vec3)  restrictions  FIM_SUPERFÍCIE
//! restrictions= RESTRIÇÕES  PONTOS_FIXOS =? int (int int){PONTOS_FIXOS}  translation*  FIM_RESTRIÇÕES
//! translation = TRANSLAÇÃO =? vec3  INI_TRANSL =? num  FIM_TRANSL =? num
//! vec3        = (? num num num )?
//! ```
//!
//! Keywords come in the printed order. `GRAVIDADE` is an anima extension (spec S3.1): the thesis has no
//! gravity keyword, so [`ParScript::to_scene`] takes the gravity to use when a script does not say.
//! Parentheses are optional but must match. The known OCR damage of Fig. 6.4 (pairs printed `90` for
//! `9 0`, `INL_TRANSL`) is rejected, not guessed at.

mod lexer;
mod parser;

use anima_cloth::flex3d::{Flex3dScene, Friction, FrictionMode, ModelOptions, SurfaceDesc, Translation};
use anima_geom::DVec3;
use anima_ode::Integrator;

use crate::ParseError;

pub use lexer::{Keyword, Token, TokenKind, Tokens, lex};

/// A `.PAR` script as written: values in the script's units (the thesis's are SI; lengths are scene
/// units), nothing defaulted that the script did not say.
#[derive(Debug, Clone, PartialEq)]
pub struct ParScript {
    /// `DURAÇÃO`, s.
    pub duration_s: f64,
    /// `QUADROS_SEG`, frames per second.
    pub frame_rate_hz: f64,
    /// `DELTA_t`, s.
    pub dt_s: f64,
    /// `FORÇA_EXTERNA`, the force on every free particle, N.
    pub external_force_n: DVec3,
    /// `ATRITO`, the friction coefficient.
    pub friction: f64,
    /// The `.OBT` file names after `OBJETOS_NA_CENA`, as written.
    pub objects: Vec<String>,
    /// `GRAVIDADE` (an anima extension), m/s²; `None` when the script does not say, as no thesis script does.
    pub gravity_m_s2: Option<DVec3>,
    pub surfaces: Vec<ParSurface>,
}

/// One `SUPERFÍCIE … FIM_SUPERFÍCIE` block.
#[derive(Debug, Clone, PartialEq)]
pub struct ParSurface {
    /// The name after `SUPERFÍCIE`; A2.2 gives none (see [`ParScript::surface_name`]).
    pub name: Option<String>,
    /// `MALHA (m n)`: rows m, columns n.
    pub rows: usize,
    pub cols: usize,
    /// `DENSIDADE`: rest spacing between neighbours.
    pub spacing_m: f64,
    /// `POSIC_NO_SRU`: the mesh centre in world coordinates.
    pub centre_m: DVec3,
    /// `VETOR_NORMAL`, non-zero, not necessarily unit.
    pub normal: DVec3,
    /// `MASSA`: the mass of each particle, kg.
    pub particle_mass_kg: f64,
    /// `CONST_ELASTICIDADE (kh kv kd)`, N/m.
    pub stiffness_n_m: [f64; 3],
    /// `CONST_CURVATURA`, one value or three.
    pub curvature: Curvature,
    /// `PONTOS_FIXOS`: (row i, column j), 0-based, in script order.
    pub fixed: Vec<(usize, usize)>,
    /// Every `TRANSLAÇÃO / INI_TRANSL / FIM_TRANSL` group, in script order.
    pub translations: Vec<Translation>,
}

/// `CONST_CURVATURA`: the grammar prints one value, every script writes three (spec S5.4 item 2,
/// ambiguity A-7).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Curvature {
    /// `CONST_CURVATURA = kc`: one constant for every angular spring.
    One(f64),
    /// `CONST_CURVATURA = (kh kv kd)`: read, by analogy with `CONST_ELASTICIDADE`, as the horizontal,
    /// vertical and diagonal angular springs.
    PerPair([f64; 3]),
}

impl Curvature {
    /// The constants of the horizontal, vertical and diagonal angular springs, N/m.
    pub fn per_pair(self) -> [f64; 3] {
        match self {
            Curvature::One(k) => [k; 3],
            Curvature::PerPair(k) => k,
        }
    }
}

/// Parses a script from its bytes, UTF-8 or Latin-1. A UTF-8 file cut inside its last character is an
/// error at that character, not a Latin-1 file.
pub fn parse(src: &[u8]) -> Result<ParScript, ParseError> {
    if let Err(e) = std::str::from_utf8(src)
        && e.error_len().is_none()
        && src.iter().any(|&b| b >= 0x80)
        && std::str::from_utf8(&src[..e.valid_up_to()]).is_ok()
        && src[e.valid_up_to()] >= 0xC0
    {
        let good = std::str::from_utf8(&src[..e.valid_up_to()]).unwrap_or_default();
        let line = 1 + good.matches('\n').count();
        let column = 1 + good.rsplit('\n').next().unwrap_or_default().chars().count();
        return Err(ParseError::new(
            line,
            column,
            "a complete UTF-8 character",
            "a character cut by the end of the file",
        ));
    }
    parse_str(&crate::text::decode(src))
}

/// Parses a script from text.
pub fn parse_str(src: &str) -> Result<ParScript, ParseError> {
    parser::script(&lex(src))
}

impl ParScript {
    /// The name of surface `k` (0-based): the script's, or `SUPERFICIE<k+1>` when it gives none (an
    /// anima convention, spec S5.2.2; ASCII because it becomes part of output file names).
    pub fn surface_name(&self, k: usize) -> String {
        self.surfaces[k].name.clone().unwrap_or_else(|| format!("SUPERFICIE{}", k + 1))
    }

    /// The scene this script describes. `gravity` applies when the script has no `GRAVIDADE`; the
    /// thesis's scripts never do, and spec S6.0 lists what each needs. Everything the language cannot
    /// say takes the specification's defaults: literal friction (A-2), the default integrator (FLEX3D's
    /// forward Euler) and [`ModelOptions::thesis`].
    pub fn to_scene(&self, gravity: DVec3) -> Flex3dScene {
        Flex3dScene {
            duration_s: self.duration_s,
            frame_rate_hz: self.frame_rate_hz,
            dt_s: self.dt_s,
            gravity_m_s2: self.gravity_m_s2.unwrap_or(gravity),
            external_force_n: self.external_force_n,
            friction: Friction { mode: FrictionMode::Literal, coefficient: self.friction },
            objects: self.objects.clone(),
            surfaces: self
                .surfaces
                .iter()
                .enumerate()
                .map(|(k, s)| SurfaceDesc {
                    name: self.surface_name(k),
                    rows: s.rows,
                    cols: s.cols,
                    spacing_m: s.spacing_m,
                    centre_m: s.centre_m,
                    normal: s.normal,
                    particle_mass_kg: s.particle_mass_kg,
                    stiffness_n_m: s.stiffness_n_m,
                    bending_n_m: s.curvature.per_pair(),
                    fixed: s.fixed.clone(),
                    translations: s.translations.clone(),
                })
                .collect(),
            integrator: Integrator::default(),
            options: ModelOptions::thesis(),
        }
    }
}
