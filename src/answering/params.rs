//! The parameter set `mavping respond` and `sim:` serve: `count`
//! parameters named `MAVPING_0000` upwards, each with a value and a type
//! that follow from its index alone, so a client's download can be held
//! against what was served without asking the server.

use crate::frame::transfer::{ParamId, ParamValue};

/// The most parameters served: four digits of name, and a
/// PARAM_REQUEST_READ's index (an i16) reaches every one.
pub(crate) const MAX_PARAMS: u16 = 10_000;

/// MAV_PARAM_TYPE of each index in turn: what ArduPilot's parameters are
/// (floats, and integers of each width), as each needs its own decoding.
const TYPES: [u8; 4] = [
    9, // REAL32
    6, // INT32
    4, // INT16
    1, // UINT8
];

/// `count` read-only parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ParamSet {
    pub(crate) count: u16,
}

impl ParamSet {
    /// Parameter `index`'s name: `MAVPING_` and its index in four digits.
    pub(crate) fn name(index: u16) -> String {
        format!("MAVPING_{index:04}")
    }

    /// The value and MAV_PARAM_TYPE of parameter `index`. Integers are sent
    /// as ArduPilot sends them, converted to a float (not bytewise), and
    /// every one is exact in a float.
    pub(crate) fn value_of(index: u16) -> (f32, u8) {
        let i = i32::from(index);
        let param_type = TYPES[usize::from(index) % TYPES.len()];
        let value = match param_type {
            9 => i as f32 * 0.25 + 0.5,
            6 => (i * 1000 - 70_000) as f32,
            4 => (i % 2000 - 1000) as f32,
            _ => (i % 256) as f32,
        };
        (value, param_type)
    }

    /// PARAM_VALUE of parameter `index`, if there is one.
    pub(crate) fn get(&self, index: u16) -> Option<ParamValue> {
        (index < self.count).then(|| {
            let (value, param_type) = Self::value_of(index);
            ParamValue {
                id: ParamId::new(&Self::name(index)),
                value,
                param_type,
                count: self.count,
                index,
            }
        })
    }

    /// The index a PARAM_REQUEST_READ asks for: `index` when it is 0 or
    /// more, else the parameter named `id` (ArduPilot and PX4 read the
    /// name when the index is -1; so do we for any negative one).
    pub(crate) fn lookup(&self, index: i16, id: &ParamId) -> Option<u16> {
        if index >= 0 {
            let index = index as u16;
            return (index < self.count).then_some(index);
        }
        let name = id.name();
        let digits = name.strip_prefix("MAVPING_")?;
        if digits.len() != 4 || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        let index: u16 = digits.parse().ok()?;
        (index < self.count).then_some(index)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_values_and_types_follow_the_index() {
        let set = ParamSet { count: 500 };
        let p = set.get(7).unwrap();
        assert_eq!(
            (p.id.name(), p.value, p.param_type, p.count, p.index),
            ("MAVPING_0007".to_string(), 7.0, 1, 500, 7)
        );
        let p = set.get(1).unwrap();
        assert_eq!((p.value, p.param_type), (-69_000.0, 6));
        assert_eq!(set.get(0).unwrap().value, 0.5);
        assert_eq!(set.get(2).unwrap().value, -998.0);
        assert_eq!(set.get(500), None);
        // Every value is an integer or a quarter: exact in a float, and
        // the same text however a client prints it.
        for i in 0..MAX_PARAMS {
            let (v, _) = ParamSet::value_of(i);
            assert_eq!((v * 4.0).fract(), 0.0);
        }
    }

    #[test]
    fn a_read_finds_by_index_or_by_name() {
        let set = ParamSet { count: 20 };
        let none = ParamId::default();
        assert_eq!(set.lookup(3, &none), Some(3));
        assert_eq!(set.lookup(20, &none), None);
        assert_eq!(set.lookup(-1, &ParamId::new("MAVPING_0019")), Some(19));
        for bad in [
            "MAVPING_0020",
            "MAVPING_19",
            "SYSID_THISMAV",
            "MAVPING_+019",
            "",
        ] {
            assert_eq!(set.lookup(-1, &ParamId::new(bad)), None, "{bad}");
        }
        // The index wins when there is one, as on ArduPilot.
        assert_eq!(set.lookup(2, &ParamId::new("MAVPING_0005")), Some(2));
    }
}
