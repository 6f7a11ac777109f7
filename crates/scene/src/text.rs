//! Bytes to text. FLEX3D ran on 1993 workstations, whose files were Latin-1; today's copies are UTF-8.

use std::borrow::Cow;

/// Decodes `bytes` as UTF-8 (dropping a byte-order mark) or, when that fails, as Latin-1, whose 256
/// byte values are the first 256 code points. Every byte string decodes, so this cannot fail; a file
/// in another encoding shows up later as a misspelt keyword at a precise position.
pub fn decode(bytes: &[u8]) -> Cow<'_, str> {
    match std::str::from_utf8(bytes) {
        Ok(s) => Cow::Borrowed(s.strip_prefix('\u{feff}').unwrap_or(s)),
        Err(_) => Cow::Owned(bytes.iter().map(|&b| char::from(b)).collect()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_utf8_and_latin1_alike() {
        assert_eq!(decode("DURAÇÃO".as_bytes()), "DURAÇÃO");
        assert_eq!(decode(b"DURA\xC7\xC3O"), "DURAÇÃO");
        assert_eq!(decode("\u{feff}ATRITO".as_bytes()), "ATRITO");
    }
}
