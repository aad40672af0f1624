//! The values of a state document, as serde types that read what one JSON value must be and
//! write the golden format back.
//!
//! A number ([`F32`]) is written as a JSON number when finite and as the string "inf", "-inf" or
//! "nan" otherwise; it is read from a number, one of those strings, or a boolean (1 or 0), and
//! must then be finite and at most [`MAX_MAGNITUDE`] in magnitude. [`Min`] (a running minimum)
//! may also be +inf, [`Angle`] must be one that `math::sin_cos` takes. A key of the document
//! that is null counts as absent: an `Option` field is `None`, a required one "is missing".
//!
//! Each type reads the JSON value whole (`serde_json::Value`) and judges it as the golden format
//! does, with the message of the refusal; `serde_path_to_error` adds the path it was found at
//! ([`parse_at`]). An object (the `object!` types) is only read from a JSON object (another
//! value lacks the first key the golden format reads of it), a list ([`List`], [`Vector`]) only
//! from a JSON list. [`Lazy`] keeps a value as it came,
//! for the parts of a document that are read only in some cases (the SNGNN frames, a group
//! member's goal radius): they are judged when read, and ignored otherwise.

use std::fmt;
use std::marker::PhantomData;

use serde::de::{self, DeserializeOwned, Deserializer, SeqAccess, Visitor};
use serde::{Deserialize, Serialize, Serializer};
use serde_json::{Map, Value};

use serde_path_to_error::Segment;

use crate::error::SimError;

/// The largest magnitude of a number in a document: positions, sums over an episode and
/// parameters stay orders of magnitude below, while squares and products of larger numbers in a
/// step would overflow f32.
pub(super) const MAX_MAGNITUDE: f32 = 1e9;

/// What a required key that is absent or null is.
const MISSING: &str = "is missing";

/// The refusal of a document at `path` (`state.humans[3].x`).
pub(super) fn err(path: &str, what: impl fmt::Display) -> SimError {
    SimError::shape("state document", format!("state document: `{path}` {what}"))
}

/// Refused when a document has `n` `what`, more than the batch's `cap`.
pub(super) fn capacity(what: &str, n: usize, cap: usize, why: &str) -> Result<(), SimError> {
    if n > cap {
        return Err(SimError::shape(
            "state document",
            format!(
                "state document has {n} {what} but the batch's capacity is {cap} ({why}); make the batch from a config whose maximum counts cover it"
            ),
        ));
    }
    Ok(())
}

/// `T` read from `value`, which sits at `prefix` in the document (empty for the document
/// itself); a refusal names the path of the offending value.
pub(super) fn parse_at<T: DeserializeOwned>(value: &Value, prefix: &str) -> Result<T, SimError> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let mut path = prefix.to_string();
        for segment in e.path().iter() {
            let segment = segment.to_string();
            if !path.is_empty() && !segment.starts_with('[') {
                path.push('.');
            }
            path.push_str(&segment);
        }
        let message = e.inner().to_string();
        let key_missing = |key: &str| match path.as_str() {
            "" => err(key, MISSING),
            path => err(&format!("{path}.{key}"), MISSING),
        };
        if let Some(first) = message.strip_prefix(NOT_AN_OBJECT) {
            // A null key is missing; any other value that is not an object (a list's element
            // included) lacks the first key read of it.
            let mut node = Some(value);
            let mut is_key = false;
            for segment in e.path().iter() {
                (node, is_key) = match segment {
                    Segment::Seq { index } => (node.and_then(|n| n.get(index)), false),
                    Segment::Map { key } => (node.and_then(|n| n.get(key)), true),
                    _ => (None, false),
                };
            }
            return match node {
                Some(Value::Null) if is_key => err(&path, MISSING),
                _ => key_missing(first),
            };
        }
        // serde's own word for a required key that is absent.
        match message
            .strip_prefix("missing field `")
            .and_then(|m| m.strip_suffix('`'))
        {
            Some(key) => key_missing(key),
            None => err(&path, message),
        }
    })
}

/// A value that one JSON value holds, judged as the golden format does.
pub(super) trait Leaf: Sized {
    /// The value of `v` (any JSON value, null included, as in a list), or the refusal.
    fn parse(v: &Value) -> Result<Self, String>;

    /// The value of a key that is null: a required key is missing.
    fn null() -> Result<Self, String> {
        Err(MISSING.into())
    }
}

/// Implements `Deserialize` for [`Leaf`] types: a key's value, where null is [`Leaf::null`].
macro_rules! leaf {
    ($($t:ty),*) => {$(
        impl<'de> Deserialize<'de> for $t {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let v = Value::deserialize(d)?;
                if v.is_null() { <$t>::null() } else { <$t>::parse(&v) }.map_err(de::Error::custom)
            }
        }
    )*};
}

/// A number, the strings "inf", "-inf" and "nan" included (booleans count as 1 and 0).
fn number(v: &Value) -> Result<f32, String> {
    match v {
        Value::Number(n) => n
            .as_f64()
            .map(|x| x as f32)
            .ok_or_else(|| "is not a number".into()),
        Value::String(s) if s == "inf" => Ok(f32::INFINITY),
        Value::String(s) if s == "-inf" => Ok(f32::NEG_INFINITY),
        Value::String(s) if s == "nan" => Ok(f32::NAN),
        Value::Bool(b) => Ok(if *b { 1.0 } else { 0.0 }),
        other => Err(format!("must be a number, got {other}")),
    }
}

/// A finite number of magnitude at most [`MAX_MAGNITUDE`].
fn finite(x: f32) -> Result<f32, String> {
    if !x.is_finite() {
        return Err(format!("is {x}; it must be finite"));
    }
    if x.abs() > MAX_MAGNITUDE {
        return Err(format!(
            "is {x}; no quantity of a state exceeds {MAX_MAGNITUDE:e} in magnitude"
        ));
    }
    Ok(x)
}

/// Writes `x` as the golden files do: a number, or "inf", "-inf", "nan".
fn write_f32<S: Serializer>(x: f32, s: S) -> Result<S::Ok, S::Error> {
    if x.is_finite() {
        s.serialize_f64(f64::from(x))
    } else if x.is_nan() {
        s.serialize_str("nan")
    } else if x > 0.0 {
        s.serialize_str("inf")
    } else {
        s.serialize_str("-inf")
    }
}

/// A finite number (m, rad, s, ... as its key says), at most [`MAX_MAGNITUDE`] in magnitude.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct F32(pub f32);

/// A finite number or +inf: a running minimum before its first sample (`metrics.v_min`,
/// `episode_sums.min_human_distance`, ...). Never NaN or -inf.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Min(pub f32);

/// An angle (rad) that `math::sin_cos` takes: |θ| ≤ 2^20 rad.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Angle(pub f32);

impl Leaf for F32 {
    fn parse(v: &Value) -> Result<Self, String> {
        finite(number(v)?).map(Self)
    }
}

impl Leaf for Min {
    fn parse(v: &Value) -> Result<Self, String> {
        match number(v)? {
            f32::INFINITY => Ok(Self(f32::INFINITY)),
            x => finite(x).map(Self),
        }
    }
}

impl Leaf for Angle {
    fn parse(v: &Value) -> Result<Self, String> {
        angle(finite(number(v)?)?).map(Self)
    }
}

/// A finite number `x` as an angle: one that `math::sin_cos` takes.
pub(super) fn angle(x: f32) -> Result<f32, String> {
    let max = crate::math::SIN_COS_MAX_ARG;
    if x.abs() > max {
        return Err(format!(
            "is {x} rad; socnav's sine and cosine take angles up to {max} rad"
        ));
    }
    Ok(x)
}

macro_rules! write_number {
    ($($t:ty),*) => {$(
        impl Serialize for $t {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                write_f32(self.0, s)
            }
        }
    )*};
}
write_number!(F32, Min, Angle);

/// A count, tick or id: an integer in 0..=u32::MAX (booleans count as 1 and 0).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
#[serde(transparent)]
pub(super) struct U32(pub u32);

impl Leaf for U32 {
    fn parse(v: &Value) -> Result<Self, String> {
        match v {
            Value::Bool(b) => Ok(Self(u32::from(*b))),
            v => v
                .as_u64()
                .and_then(|x| u32::try_from(x).ok())
                .map(Self)
                .ok_or_else(|| format!("must be an integer in 0..=4294967295, got {v}")),
        }
    }
}

/// A seed: an integer in 0..2^64.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
#[serde(transparent)]
pub(super) struct U64(pub u64);

impl Leaf for U64 {
    fn parse(v: &Value) -> Result<Self, String> {
        v.as_u64()
            .map(Self)
            .ok_or_else(|| format!("must be an integer in 0..2^64, got {v}"))
    }
}

/// A group's member: the id of a human of the `humans` list (no boolean).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
#[serde(transparent)]
pub(super) struct Id(pub u32);

impl Leaf for Id {
    fn parse(v: &Value) -> Result<Self, String> {
        v.as_u64()
            .and_then(|id| u32::try_from(id).ok())
            .map(Self)
            .ok_or_else(|| "must be a human id".into())
    }

    fn null() -> Result<Self, String> {
        Self::parse(&Value::Null)
    }
}

/// A flag: true or false; absent or null is false.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
#[serde(transparent)]
pub(super) struct Flag(pub bool);

impl Leaf for Flag {
    fn parse(v: &Value) -> Result<Self, String> {
        v.as_bool()
            .map(Self)
            .ok_or_else(|| "must be true or false".into())
    }

    fn null() -> Result<Self, String> {
        Ok(Self(false))
    }
}

/// A JSON object whose entries are judged by who reads it (`crowd_forming.slot_of`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[serde(transparent)]
pub(super) struct Object(pub Map<String, Value>);

impl Leaf for Object {
    fn parse(v: &Value) -> Result<Self, String> {
        v.as_object()
            .map(|m| Self(m.clone()))
            .ok_or_else(|| "must be an object".into())
    }
}

leaf!(F32, Min, Angle, U32, U64, Id, Flag, Object);

/// The names of a kind of thing and their codes in the state's columns.
pub(super) trait Names {
    /// Name and code of each kind.
    const CODES: &'static [(&'static str, u32)];
    /// The refusal of a name that is none of them.
    fn refuse(name: &str) -> String;
}

/// A name of the kinds `K` names, held as its code.
pub(super) struct Code<K>(pub u32, PhantomData<K>);

impl<K> Code<K> {
    pub(super) fn new(code: u32) -> Self {
        Self(code, PhantomData)
    }
}

impl<K> Default for Code<K> {
    fn default() -> Self {
        Self::new(0)
    }
}

impl<K: Names> Serialize for Code<K> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let name = K::CODES.iter().find(|(_, c)| *c == self.0);
        s.serialize_str(name.map_or("", |(n, _)| n))
    }
}

impl<'de, K: Names> Deserialize<'de> for Code<K> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        let name = match &v {
            Value::Null => return Err(de::Error::custom(MISSING)),
            Value::String(name) => name,
            _ => return Err(de::Error::custom("must be a string")),
        };
        K::CODES
            .iter()
            .find(|(n, _)| n == name)
            .map(|&(_, c)| Self::new(c))
            .ok_or_else(|| de::Error::custom(K::refuse(name)))
    }
}

/// A value kept as it came, judged when read ([`Lazy::get`]); `Ready` when written.
#[derive(Clone, Debug)]
pub(super) enum Lazy<T> {
    /// A value to write.
    Ready(T),
    /// A value as a document holds it.
    Raw(Value),
}

impl<T: DeserializeOwned + Clone> Lazy<T> {
    /// The value, read from the document at `path`.
    pub(super) fn get(&self, path: &str) -> Result<T, SimError> {
        match self {
            Self::Ready(t) => Ok(t.clone()),
            Self::Raw(v) => parse_at(v, path),
        }
    }
}

impl<T: Serialize> Serialize for Lazy<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Self::Ready(t) => t.serialize(s),
            Self::Raw(v) => v.serialize(s),
        }
    }
}

impl<'de, T> Deserialize<'de> for Lazy<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Value::deserialize(d).map(Self::Raw)
    }
}

/// The refusal of a value of another kind than a list, `null_missing`: a null one is missing.
fn not_a_list<E: de::Error>(null_missing: bool, null: bool) -> E {
    E::custom(if null && null_missing {
        MISSING
    } else {
        "must be a list"
    })
}

/// The visitor methods of a value that must be a list: what is not one is refused.
macro_rules! only_lists {
    ($null_missing:expr, $on_null:expr) => {
        fn visit_bool<E: de::Error>(self, _: bool) -> Result<Self::Value, E> {
            Err(not_a_list($null_missing, false))
        }
        fn visit_i64<E: de::Error>(self, _: i64) -> Result<Self::Value, E> {
            Err(not_a_list($null_missing, false))
        }
        fn visit_u64<E: de::Error>(self, _: u64) -> Result<Self::Value, E> {
            Err(not_a_list($null_missing, false))
        }
        fn visit_f64<E: de::Error>(self, _: f64) -> Result<Self::Value, E> {
            Err(not_a_list($null_missing, false))
        }
        fn visit_str<E: de::Error>(self, _: &str) -> Result<Self::Value, E> {
            Err(not_a_list($null_missing, false))
        }
        fn visit_map<A: de::MapAccess<'de>>(self, _: A) -> Result<Self::Value, A::Error> {
            Err(not_a_list($null_missing, false))
        }
        fn visit_unit<E: de::Error>(self) -> Result<Self::Value, E> {
            $on_null
        }
    };
}

/// A list of `T`: absent or null is empty, unless `REQUIRED` (then it is missing).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct List<T, const REQUIRED: bool = false>(pub Vec<T>);

impl<T, const R: bool> Default for List<T, R> {
    fn default() -> Self {
        Self(Vec::new())
    }
}

impl<T: Serialize, const R: bool> Serialize for List<T, R> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}

impl<'de, T: Deserialize<'de>, const R: bool> Deserialize<'de> for List<T, R> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T, const R: bool>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>, const R: bool> Visitor<'de> for V<T, R> {
            type Value = List<T, R>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a list")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut items = Vec::new();
                while let Some(item) = seq.next_element()? {
                    items.push(item);
                }
                Ok(List(items))
            }
            only_lists!(
                R,
                if R {
                    Err(not_a_list(true, true))
                } else {
                    Ok(List(Vec::new()))
                }
            );
        }
        d.deserialize_any(V::<T, R>(PhantomData))
    }
}

/// An element of a list: null is not missing but a value of the wrong kind.
struct Elem<T>(T);

impl<'de, T: Leaf> Deserialize<'de> for Elem<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        T::parse(&v).map(Elem).map_err(de::Error::custom)
    }
}

/// Reads a list of exactly the `n` elements that `read` takes (`size_hint` is exact for a JSON
/// document), refused with `wrong` (given the length) before any element is read otherwise.
fn fixed<'de, A: SeqAccess<'de>, T>(
    mut seq: A,
    n: usize,
    wrong: impl FnOnce(usize) -> String,
    read: impl FnOnce(&mut A) -> Result<T, A::Error>,
) -> Result<T, A::Error> {
    let len = match seq.size_hint() {
        Some(len) => len,
        None => {
            // Not a JSON document's list: read it whole to count it.
            let mut items = Vec::new();
            while let Some(v) = seq.next_element::<Value>()? {
                items.push(v);
            }
            return Err(de::Error::custom(if items.len() == n {
                "must be a list of known length".to_string()
            } else {
                wrong(items.len())
            }));
        }
    };
    if len != n {
        return Err(de::Error::custom(wrong(len)));
    }
    let value = read(&mut seq)?;
    while seq.next_element::<de::IgnoredAny>()?.is_some() {}
    Ok(value)
}

/// The next element of a list whose length was checked.
fn next<'de, A: SeqAccess<'de>, T: Leaf>(seq: &mut A) -> Result<T, A::Error> {
    match seq.next_element::<Elem<T>>()? {
        Some(Elem(t)) => Ok(t),
        None => Err(de::Error::custom("ended early")),
    }
}

/// A list of exactly `N` finite numbers (a position, a velocity).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Vector<const N: usize>(pub [f32; N]);

impl<const N: usize> Default for Vector<N> {
    fn default() -> Self {
        Self([0.0; N])
    }
}

impl<const N: usize> Serialize for Vector<N> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.map(F32).serialize(s)
    }
}

impl<'de, const N: usize> Deserialize<'de> for Vector<N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<const N: usize>;
        impl<'de, const N: usize> Visitor<'de> for V<N> {
            type Value = Vector<N>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a list")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Vector<N>, A::Error> {
                let wrong = |len| format!("must hold {N} numbers, got {len}");
                fixed(seq, N, wrong, |seq| {
                    let mut out = [0.0; N];
                    for o in &mut out {
                        *o = next::<_, F32>(seq)?.0;
                    }
                    Ok(Vector(out))
                })
            }
            only_lists!(true, Err(not_a_list(true, true)));
        }
        d.deserialize_any(V::<N>)
    }
}

/// A forming crowd's slot: `[x, y, theta]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub(super) struct Slot(pub F32, pub F32, pub Angle);

/// A replayed group noise: `[member_id, noise_x, noise_y]` (golden episodes only).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub(super) struct Noise(pub U32, pub F32, pub F32);

/// Implements `Deserialize` for a three-element list type `$t` of leaves `$a`, `$b`, `$c`
/// (a null list is not missing: these are list elements).
macro_rules! triple {
    ($t:ident, $a:ty, $b:ty, $c:ty, $wrong:expr) => {
        impl<'de> Deserialize<'de> for $t {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                struct V;
                impl<'de> Visitor<'de> for V {
                    type Value = $t;
                    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                        f.write_str("a list")
                    }
                    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<$t, A::Error> {
                        fixed(
                            seq,
                            3,
                            |_| $wrong.to_string(),
                            |seq| {
                                Ok($t(
                                    next::<_, $a>(seq)?,
                                    next::<_, $b>(seq)?,
                                    next::<_, $c>(seq)?,
                                ))
                            },
                        )
                    }
                    only_lists!(false, Err(not_a_list(false, true)));
                }
                d.deserialize_any(V)
            }
        }
    };
}
triple!(Slot, F32, F32, Angle, "must be [x, y, theta]");
triple!(
    Noise,
    U32,
    F32,
    F32,
    "must be [member_id, noise_x, noise_y]"
);

/// Starts the message of a value that is not an object, followed by the first key the golden
/// format reads of it; [`parse_at`] words it as that key missing (or, for a null key, the key
/// itself), as the path of the first value read names what is wrong.
pub(super) const NOT_AN_OBJECT: &str = "\u{1}";

/// Implements `Serialize` and `Deserialize` for structs derived with `#[serde(remote = "Self")]`:
/// written as derived, read only from a JSON object (a derived struct also takes a list of its
/// fields in order, which the golden format does not have).
macro_rules! object {
    ($($t:ident: $first:literal),* $(,)?) => {$(
        impl serde::Serialize for $t {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                $t::serialize(self, s)
            }
        }
        impl<'de> serde::Deserialize<'de> for $t {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                use serde::de::{MapAccess, SeqAccess, Visitor, Error};
                fn not_an_object<E: Error>() -> E {
                    E::custom(format!("{}{}", $crate::document::values::NOT_AN_OBJECT, $first))
                }
                struct V;
                impl<'de> Visitor<'de> for V {
                    type Value = $t;
                    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                        f.write_str("an object")
                    }
                    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<$t, A::Error> {
                        $t::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    }
                    fn visit_unit<E: Error>(self) -> Result<$t, E> {
                        Err(not_an_object())
                    }
                    fn visit_bool<E: Error>(self, _: bool) -> Result<$t, E> {
                        Err(not_an_object())
                    }
                    fn visit_i64<E: Error>(self, _: i64) -> Result<$t, E> {
                        Err(not_an_object())
                    }
                    fn visit_u64<E: Error>(self, _: u64) -> Result<$t, E> {
                        Err(not_an_object())
                    }
                    fn visit_f64<E: Error>(self, _: f64) -> Result<$t, E> {
                        Err(not_an_object())
                    }
                    fn visit_str<E: Error>(self, _: &str) -> Result<$t, E> {
                        Err(not_an_object())
                    }
                    fn visit_seq<A: SeqAccess<'de>>(self, _: A) -> Result<$t, A::Error> {
                        Err(not_an_object())
                    }
                }
                d.deserialize_any(V)
            }
        }
    )*};
}
pub(super) use object;
