//! Controller parameters (Nunes 2006 §4.3, Fig. 4.5; spec §6.10): every number a controller file
//! holds — machine weights, target angles, interpolation delays, transition times, sensor parameters,
//! oscillation delays — lives in one flat table of `f64` values, addressed by [`ParamId`].
//!
//! Why a flat table: an optimiser sees the controller as a point in ℝⁿ, procedures change parameters
//! on line by id, and the per-iteration step reads values without chasing pointers. A parameter given
//! in the file with an admissible interval is *free* (an optimiser may change it); a bare number is
//! fixed.

use std::fmt;

use serde::de::{self, MapAccess, Visitor};
use serde::ser::SerializeStruct;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A number in a controller file: a bare value (fixed), or a value with its admissible interval
/// (free for the optimisers). In RON: `0.25`, or `(value: 0.25, min: -0.25, max: 0.75)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Param {
    pub value: f64,
    /// Admissible interval [min, max]; `None` for a fixed parameter.
    pub range: Option<(f64, f64)>,
}

impl Param {
    /// A fixed parameter.
    pub fn fixed(value: f64) -> Self {
        Self { value, range: None }
    }

    /// A free parameter with admissible interval [min, max].
    pub fn free(value: f64, min: f64, max: f64) -> Self {
        Self { value, range: Some((min, max)) }
    }
}

impl Serialize for Param {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self.range {
            None => s.serialize_f64(self.value),
            Some((min, max)) => {
                let mut st = s.serialize_struct("Param", 3)?;
                st.serialize_field("value", &self.value)?;
                st.serialize_field("min", &min)?;
                st.serialize_field("max", &max)?;
                st.end()
            }
        }
    }
}

impl<'de> Deserialize<'de> for Param {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct ParamVisitor;
        impl<'de> Visitor<'de> for ParamVisitor {
            type Value = Param;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number, or (value: v, min: a, max: b)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Param, E> {
                Ok(Param::fixed(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Param, E> {
                Ok(Param::fixed(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Param, E> {
                Ok(Param::fixed(v as f64))
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Param, A::Error> {
                let (mut value, mut min, mut max) = (None, None, None);
                while let Some(key) = map.next_key::<String>()? {
                    let slot = match key.as_str() {
                        "value" => &mut value,
                        "min" => &mut min,
                        "max" => &mut max,
                        other => return Err(de::Error::unknown_field(other, &["value", "min", "max"])),
                    };
                    if slot.is_some() {
                        return Err(de::Error::custom(format_args!("duplicate field `{key}`")));
                    }
                    *slot = Some(map.next_value::<f64>()?);
                }
                let value = value.ok_or_else(|| de::Error::missing_field("value"))?;
                match (min, max) {
                    (Some(a), Some(b)) => Ok(Param::free(value, a, b)),
                    (None, None) => Ok(Param::fixed(value)),
                    _ => Err(de::Error::custom("an interval needs both `min` and `max`")),
                }
            }
        }
        d.deserialize_any(ParamVisitor)
    }
}

/// Index of a parameter in a controller's table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct ParamId(pub usize);

/// The parameter types of Fig. 4.5 (spec §6.10) that carry numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ParamKind {
    /// A machine's weight, P_ME of Eq. 5.1; ≥ 0.
    Weight,
    /// A target angle of a state's pose, rad.
    TargetAngle,
    /// A transition's interpolation delay D_I, whole iterations ≥ 0.
    InterpolationDelay,
    /// A temporal transition's time τ, whole iterations ≥ 0.
    Time,
    /// A parameter of a sensor (of a sensory transition or of the sensor set); meaning set by the
    /// designer.
    SensorParam,
    /// A machine sensor's oscillation delay (hold-off), whole iterations ≥ 0.
    OscillationDelay,
    /// A gain of a feedback target (θ₀ + Σ gainᵢ · sensorᵢ); any sign.
    FeedbackGain,
}

impl ParamKind {
    /// Whole iterations: values are rounded to the nearest integer when set.
    pub fn is_integer(self) -> bool {
        matches!(self, Self::InterpolationDelay | Self::Time | Self::OscillationDelay)
    }

    /// Kinds that cannot be negative.
    pub fn is_non_negative(self) -> bool {
        !matches!(self, Self::TargetAngle | Self::SensorParam | Self::FeedbackGain)
    }
}

/// Where a parameter sits in the controller's tree, for the hierarchical selection of spec §7.2.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ParamOwner {
    /// A machine's own parameter (its weight).
    Machine { machine: usize },
    /// A target angle of a state's pose (of the state that owns the pose).
    State { machine: usize, state: usize },
    /// A transition's delay, time or sensor parameter.
    Transition { machine: usize, transition: usize },
    /// A parameter of a sensor of the controller's sensor set.
    Sensor { sensor: usize },
}

/// One entry of the parameter table.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamInfo {
    /// Path of the number in the controller file, e.g. `machines[0].transitions[1].when.params[0]`.
    pub path: String,
    /// A readable name, e.g. `W-LEGS/T2/p0` or `W-LEGS/E1/hip_l`.
    pub label: String,
    pub kind: ParamKind,
    /// Admissible interval; `None` for a fixed parameter.
    pub range: Option<(f64, f64)>,
    pub owner: ParamOwner,
    /// Every "automatically modifiable" flag on the way from the machine (or sensor) down to this
    /// parameter is set (spec §7.2).
    pub auto: bool,
}

impl ParamInfo {
    /// The value `v` as this parameter stores it: rounded for whole-iteration kinds.
    pub fn normalise(&self, v: f64) -> f64 {
        if self.kind.is_integer() { v.round() } else { v }
    }

    /// Free for the optimisers: it has an interval and every flag above it allows modification.
    pub fn is_free(&self) -> bool {
        self.range.is_some() && self.auto
    }
}
