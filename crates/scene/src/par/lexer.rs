//! Tokens of the `.PAR` language (spec S5.2.2, lexical rules).
//!
//! Tokens are separated by whitespace, and line breaks carry no meaning. `(`, `)` and `=` are tokens of
//! their own even when glued to a number, as the thesis writes them: `(0.0`, `10.0)`, `DELTA_t=0.001`.

use std::fmt;

/// What a token is. Numbers, names and keywords are all words; the parser decides which it needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TokenKind {
    LParen,
    RParen,
    Equals,
    Word,
}

/// A token and where it starts: 1-based line and column, counted in characters.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Token {
    pub kind: TokenKind,
    pub text: String,
    pub line: usize,
    pub column: usize,
}

impl Token {
    /// The keyword this word spells, if any.
    pub fn keyword(&self) -> Option<Keyword> {
        if self.kind == TokenKind::Word { Keyword::from_word(&self.text) } else { None }
    }
}

/// The tokens of `src` and the end-of-file position, which is just after the last token: an error
/// "found end of file" then points where the missing text should go, not at trailing blank lines.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Tokens {
    pub tokens: Vec<Token>,
    pub eof_line: usize,
    pub eof_column: usize,
}

/// Splits `src` into tokens. Lexing cannot fail: anything that is not whitespace or `( ) =` is a word.
pub fn lex(src: &str) -> Tokens {
    let mut tokens = Vec::new();
    let (mut line, mut column) = (1, 1);
    let (mut eof_line, mut eof_column) = (1, 1);
    let mut word: Option<Token> = None;
    for c in src.chars() {
        let single = match c {
            '(' => Some(TokenKind::LParen),
            ')' => Some(TokenKind::RParen),
            '=' => Some(TokenKind::Equals),
            _ => None,
        };
        if c.is_whitespace() || single.is_some() {
            tokens.extend(word.take());
        }
        if let Some(kind) = single {
            tokens.push(Token { kind, text: c.to_string(), line, column });
        } else if !c.is_whitespace() {
            word.get_or_insert_with(|| Token { kind: TokenKind::Word, text: String::new(), line, column })
                .text
                .push(c);
        }
        if c == '\n' {
            line += 1;
            column = 1;
        } else {
            column += 1;
        }
        if !c.is_whitespace() {
            (eof_line, eof_column) = (line, column);
        }
    }
    tokens.extend(word);
    Tokens { tokens, eof_line, eof_column }
}

/// The keywords of the language. Matching is case-insensitive and ignores the Portuguese accents, so
/// `DURAÇÃO`, `DURACAO` and `Duração` are one keyword; the thesis's own variant `RESTRICÇÕES` (§5.2.2
/// text, Figs. 6.4, A2.4, A2.8) is accepted beside the grammar's `RESTRIÇÕES` (spec S5.4 item 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Keyword {
    Duracao,
    QuadrosSeg,
    DeltaT,
    ForcaExterna,
    Atrito,
    ObjetosNaCena,
    /// Gravity vector, an anima extension; not in the thesis (spec S3.1).
    Gravidade,
    NumSuperficies,
    Superficie,
    Malha,
    Densidade,
    PosicNoSru,
    VetorNormal,
    Massa,
    ConstElasticidade,
    ConstCurvatura,
    Restricoes,
    PontosFixos,
    Translacao,
    IniTransl,
    FimTransl,
    FimRestricoes,
    FimSuperficie,
}

impl Keyword {
    /// The spelling of the printed grammar (§5.2.1), used in messages.
    pub fn spelling(self) -> &'static str {
        match self {
            Keyword::Duracao => "DURAÇÃO",
            Keyword::QuadrosSeg => "QUADROS_SEG",
            Keyword::DeltaT => "DELTA_t",
            Keyword::ForcaExterna => "FORÇA_EXTERNA",
            Keyword::Atrito => "ATRITO",
            Keyword::ObjetosNaCena => "OBJETOS_NA_CENA",
            Keyword::Gravidade => "GRAVIDADE",
            Keyword::NumSuperficies => "NUM_SUPERFÍCIES",
            Keyword::Superficie => "SUPERFÍCIE",
            Keyword::Malha => "MALHA",
            Keyword::Densidade => "DENSIDADE",
            Keyword::PosicNoSru => "POSIC_NO_SRU",
            Keyword::VetorNormal => "VETOR_NORMAL",
            Keyword::Massa => "MASSA",
            Keyword::ConstElasticidade => "CONST_ELASTICIDADE",
            Keyword::ConstCurvatura => "CONST_CURVATURA",
            Keyword::Restricoes => "RESTRIÇÕES",
            Keyword::PontosFixos => "PONTOS_FIXOS",
            Keyword::Translacao => "TRANSLAÇÃO",
            Keyword::IniTransl => "INI_TRANSL",
            Keyword::FimTransl => "FIM_TRANSL",
            Keyword::FimRestricoes => "FIM_RESTRIÇÕES",
            Keyword::FimSuperficie => "FIM_SUPERFÍCIE",
        }
    }

    /// The keyword `word` spells in any accepted form, or `None`.
    pub fn from_word(word: &str) -> Option<Keyword> {
        Some(match fold(word).as_str() {
            "DURACAO" => Keyword::Duracao,
            "QUADROS_SEG" => Keyword::QuadrosSeg,
            "DELTA_T" => Keyword::DeltaT,
            "FORCA_EXTERNA" => Keyword::ForcaExterna,
            "ATRITO" => Keyword::Atrito,
            "OBJETOS_NA_CENA" => Keyword::ObjetosNaCena,
            "GRAVIDADE" => Keyword::Gravidade,
            "NUM_SUPERFICIES" => Keyword::NumSuperficies,
            "SUPERFICIE" => Keyword::Superficie,
            "MALHA" => Keyword::Malha,
            "DENSIDADE" => Keyword::Densidade,
            "POSIC_NO_SRU" => Keyword::PosicNoSru,
            "VETOR_NORMAL" => Keyword::VetorNormal,
            "MASSA" => Keyword::Massa,
            "CONST_ELASTICIDADE" => Keyword::ConstElasticidade,
            "CONST_CURVATURA" => Keyword::ConstCurvatura,
            "RESTRICOES" | "RESTRICCOES" => Keyword::Restricoes,
            "PONTOS_FIXOS" => Keyword::PontosFixos,
            "TRANSLACAO" => Keyword::Translacao,
            "INI_TRANSL" => Keyword::IniTransl,
            "FIM_TRANSL" => Keyword::FimTransl,
            "FIM_RESTRICOES" | "FIM_RESTRICCOES" => Keyword::FimRestricoes,
            "FIM_SUPERFICIE" => Keyword::FimSuperficie,
            _ => return None,
        })
    }
}

impl fmt::Display for Keyword {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "`{}`", self.spelling())
    }
}

/// Upper case with the accents of Portuguese removed: `Superfície` → `SUPERFICIE`.
fn fold(word: &str) -> String {
    word.chars()
        .flat_map(char::to_uppercase)
        .map(|c| match c {
            'Á' | 'À' | 'Â' | 'Ã' | 'Ä' => 'A',
            'É' | 'È' | 'Ê' | 'Ë' => 'E',
            'Í' | 'Ì' | 'Î' | 'Ï' => 'I',
            'Ó' | 'Ò' | 'Ô' | 'Õ' | 'Ö' => 'O',
            'Ú' | 'Ù' | 'Û' | 'Ü' => 'U',
            'Ç' => 'C',
            c => c,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texts(src: &str) -> Vec<(String, usize, usize)> {
        lex(src).tokens.into_iter().map(|t| (t.text, t.line, t.column)).collect()
    }

    #[test]
    fn splits_parentheses_and_equals_off_glued_numbers() {
        let t = texts("FORÇA_EXTERNA=(0.0 -0.39\n  0.2)");
        let expect = [
            ("FORÇA_EXTERNA", 1, 1),
            ("=", 1, 14),
            ("(", 1, 15),
            ("0.0", 1, 16),
            ("-0.39", 1, 20),
            ("0.2", 2, 3),
            (")", 2, 6),
        ];
        assert_eq!(t, expect.map(|(s, l, c)| (s.to_owned(), l, c)));
    }

    #[test]
    fn columns_count_characters_not_bytes() {
        // "DURAÇÃO" is 7 characters but 9 bytes.
        let t = lex("DURAÇÃO = 25");
        assert_eq!((t.tokens[1].column, t.tokens[2].column), (9, 11));
        assert_eq!((t.eof_line, t.eof_column), (1, 13));
    }

    #[test]
    fn end_of_file_is_just_after_the_last_token() {
        let t = lex("FIM_SUPERFÍCIE\n\n  \n");
        assert_eq!((t.eof_line, t.eof_column), (1, 15));
        assert_eq!((lex("").eof_line, lex("").eof_column), (1, 1));
    }

    #[test]
    fn keywords_in_every_accepted_spelling() {
        for w in ["RESTRIÇÕES", "RESTRICÇÕES", "restricoes", "RESTRICCOES", "Restrições"] {
            assert_eq!(Keyword::from_word(w), Some(Keyword::Restricoes), "{w}");
        }
        for w in ["FIM_RESTRIÇÕES", "FIM_RESTRICÇÕES", "FIM_RESTRICOES"] {
            assert_eq!(Keyword::from_word(w), Some(Keyword::FimRestricoes), "{w}");
        }
        assert_eq!(Keyword::from_word("DELTA_t"), Some(Keyword::DeltaT));
        assert_eq!(Keyword::from_word("NUM_SUPERFICIES"), Some(Keyword::NumSuperficies));
        assert_eq!(Keyword::from_word("INL_TRANSL"), None);
    }
}
