//! An optional number written plainly in a RON file: `frame_rate_hz: 30.0`, not
//! `frame_rate_hz: Some(30.0)`, for a field that may be left out (`#[serde(default, with =
//! "anima_format::optional_number", skip_serializing_if = "Option::is_none")]`). Used where a schema
//! reads a field under its new name or an older one, and exactly one of them is given.

use serde::{Deserialize, Deserializer, Serializer};

/// A plain number as `Some`; a field left out is `None` by the field's `default`.
pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    f64::deserialize(d).map(Some)
}

/// `Some(x)` as the plain number x (a `None` field is skipped by `skip_serializing_if`).
pub fn serialize<S: Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
    match v {
        Some(x) => s.serialize_f64(*x),
        None => s.serialize_none(),
    }
}

#[cfg(test)]
mod tests {
    #[derive(Debug, PartialEq, serde::Serialize, serde::Deserialize)]
    struct Clock {
        #[serde(default, with = "super", skip_serializing_if = "Option::is_none")]
        rate: Option<f64>,
        #[serde(default, with = "super", skip_serializing_if = "Option::is_none")]
        interval: Option<f64>,
    }

    #[test]
    fn a_plain_number_reads_as_some_and_a_missing_field_as_none_and_both_write_back() {
        let clock: Clock = ron::from_str("Clock(rate: 30.0)").unwrap();
        assert_eq!(clock, Clock { rate: Some(30.0), interval: None });
        let text = ron::to_string(&clock).unwrap();
        assert_eq!(text, "(rate:30.0)");
        assert_eq!(ron::from_str::<Clock>(&text).unwrap(), clock);
        assert!(ron::from_str::<Clock>("Clock(rate: Some(30.0))").is_err(), "the plain form only");
    }
}
