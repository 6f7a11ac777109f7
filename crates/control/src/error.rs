//! Errors of controller files: what is wrong, in which field, and at which line and column.
//!
//! The form is the one every anima description file shares ([`anima_format::FieldError`]): ron reports
//! where it stopped reading but not in which field, the controller's checks know the field path but not
//! the line, and `anima_format`'s RON field-path scanner joins the two.

/// What kind of problem a controller file has.
pub type ControllerErrorKind = anima_format::FieldErrorKind;

/// A controller that could not be read or built: the field path
/// (`machines[0].transitions[2].when.params[0]`), its line and column when it came from text, and what
/// is wrong.
pub type ControllerError = anima_format::FieldError;
