//! File-format errors shared by every anima reader: where a file is wrong and what was expected there.
//!
//! Every scene, skeleton and controller file of anima is text a person writes, so every error names
//! the file, the line and the column, what the reader expected and what it found. Two kinds of error
//! share that promise:
//!
//! - [`ParseError`]: the text does not follow the grammar (a `.PAR` keyword, a RON field of the wrong
//!   type). ron's own errors become `expected …, found …` through [`ron_text::from_str`].
//! - [`FieldError`]: the text parses but describes nothing valid (a negative mass, an unknown body),
//!   found by checks that know the field's path (`bodies[3].mass`) but not its line. The RON
//!   field-path scanner of [`ron_path`] joins the two without a second parser.
//!
//! [`ron_text::struct_name`] sniffs which struct a RON file holds, so a reader can tell a file's kind
//! without parsing it twice.
//!
//! [`optional_number`] reads and writes a field that may be left out as a plain number.
//!
//! [`limits`] holds the largest counts any reader accepts (particles, steps, bodies, states, an
//! optimiser's population and budget), so that every file kind is checked against the same numbers.
//!
//! This crate does no file I/O and knows no anima type: it is the leaf that `anima-body`,
//! `anima-control` and `anima-scene` read their files through.
//!
//! ```
//! #[derive(Debug, serde::Deserialize)]
//! struct Spring { stiffness_n_m: f64 }
//!
//! let text = "Spring(\n    stiffness_n_m: stiff,\n)";
//! assert_eq!(anima_format::ron_text::struct_name(text), Some("Spring"));
//! let e = anima_format::ron_text::from_str::<Spring>(text).unwrap_err().with_file("spring.ron");
//! assert_eq!((e.line, e.column), (2, 20));
//! assert_eq!(e.to_string(), "spring.ron:2:20: expected float, found \"stiff\"");
//! ```

mod error;
pub mod limits;
pub mod optional_number;
pub mod ron_path;
pub mod ron_text;

pub use error::{END_OF_FILE, FieldError, FieldErrorKind, ParseError, not_a_plain_name, utf8};
