//! msgpack values for numpy arrays and images, in the two dialects model servers decode:
//! openpi's msgpack-numpy (marker keys as msgpack *bin*: `b"__ndarray__"`, `b"data"`, ...) and
//! vla-eval's (the same keys as *str*, plus `__image__` maps for PNG or raw images).
//!
//! It does not frame or transport anything (see `link`).

use results::profile::StateDtype;
use rmpv::Value;

/// How marker keys are spelled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Keys {
    /// openpi: msgpack bin, which Python unpacks as `bytes`.
    Binary,
    /// vla-eval: msgpack str.
    Text,
}

fn key(keys: Keys, k: &str) -> Value {
    match keys {
        Keys::Binary => Value::Binary(k.as_bytes().to_vec()),
        Keys::Text => Value::String(k.into()),
    }
}

pub fn str(s: &str) -> Value {
    Value::String(s.into())
}

/// A map with str keys.
pub fn map(entries: Vec<(&str, Value)>) -> Value {
    Value::Map(entries.into_iter().map(|(k, v)| (str(k), v)).collect())
}

fn ndarray(keys: Keys, data: Vec<u8>, dtype: &str, shape: &[usize]) -> Value {
    Value::Map(vec![
        (key(keys, "__ndarray__"), Value::Boolean(true)),
        (key(keys, "data"), Value::Binary(data)),
        (key(keys, "dtype"), Value::String(dtype.into())),
        (
            key(keys, "shape"),
            Value::Array(shape.iter().map(|&s| Value::from(s as u64)).collect()),
        ),
    ])
}

/// A 1-d float array.
pub fn floats(keys: Keys, values: &[f64], dtype: StateDtype) -> Value {
    let (data, code) = match dtype {
        StateDtype::Float32 => (
            values
                .iter()
                .flat_map(|v| (*v as f32).to_le_bytes())
                .collect(),
            "<f4",
        ),
        StateDtype::Float64 => (values.iter().flat_map(|v| v.to_le_bytes()).collect(), "<f8"),
    };
    ndarray(keys, data, code, &[values.len()])
}

/// An RGB image as a uint8 HWC array.
pub fn image_array(keys: Keys, rgb: &[u8], width: usize, height: usize) -> Value {
    ndarray(keys, rgb.to_vec(), "|u1", &[height, width, 3])
}

/// An RGB image as vla-eval's `__image__` map, PNG-compressed or raw.
pub fn image_vla_eval(rgb: &[u8], width: usize, height: usize, png: bool) -> Value {
    let shape = Value::Array(vec![
        Value::from(height as u64),
        Value::from(width as u64),
        Value::from(3u64),
    ]);
    if !png {
        return map(vec![
            ("__image__", Value::Boolean(true)),
            ("format", str("raw")),
            ("data", Value::Binary(rgb.to_vec())),
            ("dtype", str("|u1")),
            ("shape", shape),
        ]);
    }
    let mut out = Vec::with_capacity(rgb.len() / 2);
    {
        let mut enc = png::Encoder::new(&mut out, width as u32, height as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        // Writing into memory cannot fail for a well-formed RGB buffer.
        let mut w = enc.write_header().expect("png header into memory");
        w.write_image_data(rgb).expect("png data into memory");
    }
    map(vec![
        ("__image__", Value::Boolean(true)),
        ("format", str("png")),
        ("data", Value::Binary(out)),
        ("shape", shape),
    ])
}

/// The value under `k` (str or bin key) in a map.
pub fn get<'v>(v: &'v Value, k: &str) -> Option<&'v Value> {
    v.as_map()?.iter().find_map(|(mk, mv)| {
        let hit = match mk {
            Value::String(s) => s.as_str() == Some(k),
            Value::Binary(b) => b.as_slice() == k.as_bytes(),
            _ => false,
        };
        hit.then_some(mv)
    })
}

/// Why a reply's actions are not a float matrix or vector.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ActionsError {
    /// The actions value's kind ([`kind_of`]).
    #[error("the actions are {0}, not an array")]
    NotAnArray(&'static str),
    /// A component's kind ([`kind_of`]).
    #[error("an action component is {0}, not a number")]
    NotANumber(&'static str),
    #[error("the array has no dtype")]
    NoDtype,
    #[error("the array has no binary data")]
    NoData,
    #[error("the array has no shape")]
    NoShape,
    #[error("the array's shape is not a list of sizes")]
    BadShape,
    #[error("the actions have dtype `{0}`, not a float or integer type")]
    Dtype(String),
    #[error("the array's data has {bytes} bytes, which is not shape {shape:?} of `{dtype}`")]
    DataSize {
        bytes: usize,
        shape: Vec<usize>,
        dtype: String,
    },
    #[error("the actions have shape {0:?}; expected (chunk, dim) or (dim,)")]
    Shape(Vec<usize>),
}

/// Why bytes are not one msgpack value.
#[derive(Debug, thiserror::Error)]
pub enum DecodeError {
    /// `len`: the bytes' length.
    #[error("not msgpack ({len} bytes): {source}")]
    NotMsgpack {
        len: usize,
        source: rmpv::decode::Error,
    },
    /// `rest` of the `len` bytes follow the first value.
    #[error("not msgpack: {rest} of its {len} bytes follow the first value")]
    Trailing { rest: usize, len: usize },
}

/// A float matrix (an action chunk) or vector (one action), from a numpy array in either dialect
/// or nested msgpack arrays of numbers. Returns rows; a vector is one row.
pub fn actions(v: &Value) -> Result<Vec<Vec<f64>>, ActionsError> {
    if get(v, "__ndarray__").is_some() {
        return ndarray_rows(v);
    }
    match v {
        Value::Array(rows) if rows.iter().all(|r| matches!(r, Value::Array(_))) => rows
            .iter()
            .map(|r| number_list(r.as_array().expect("checked above")))
            .collect(),
        Value::Array(xs) => Ok(vec![number_list(xs)?]),
        other => Err(ActionsError::NotAnArray(kind_of(other))),
    }
}

fn number_list(xs: &[Value]) -> Result<Vec<f64>, ActionsError> {
    xs.iter()
        .map(|x| {
            x.as_f64()
                .or_else(|| x.as_i64().map(|i| i as f64))
                .or_else(|| x.as_u64().map(|u| u as f64))
                .ok_or_else(|| ActionsError::NotANumber(kind_of(x)))
        })
        .collect()
}

fn ndarray_rows(v: &Value) -> Result<Vec<Vec<f64>>, ActionsError> {
    let dtype = get(v, "dtype")
        .and_then(|d| d.as_str())
        .ok_or(ActionsError::NoDtype)?;
    let data = match get(v, "data") {
        Some(Value::Binary(b)) => b.as_slice(),
        _ => return Err(ActionsError::NoData),
    };
    let shape: Vec<usize> = get(v, "shape")
        .and_then(|s| s.as_array())
        .ok_or(ActionsError::NoShape)?
        .iter()
        .map(|d| d.as_u64().map(|d| d as usize))
        .collect::<Option<_>>()
        .ok_or(ActionsError::BadShape)?;
    let (width, big, float) = match dtype.as_bytes() {
        [e @ (b'<' | b'>' | b'='), b'f', w @ (b'4' | b'8')] => {
            (usize::from(*w - b'0'), *e == b'>', true)
        }
        [
            e @ (b'<' | b'>' | b'=' | b'|'),
            b'i' | b'u',
            w @ (b'1' | b'2' | b'4' | b'8'),
        ] => (usize::from(*w - b'0'), *e == b'>', false),
        _ => return Err(ActionsError::Dtype(dtype.to_string())),
    };
    // A declared shape is untrusted: its product may overflow.
    let need = shape
        .iter()
        .try_fold(width, |n, &d| n.checked_mul(d))
        .filter(|&n| n == data.len());
    if need.is_none() {
        return Err(ActionsError::DataSize {
            bytes: data.len(),
            shape,
            dtype: dtype.to_string(),
        });
    }
    let signed = dtype.as_bytes()[1] == b'i';
    let values: Vec<f64> = data
        .chunks_exact(width)
        .map(|c| {
            let mut b = [0u8; 8];
            if big {
                b[..width].copy_from_slice(c);
                b[..width].reverse();
            } else {
                b[..width].copy_from_slice(c);
            }
            match (float, width) {
                (true, 4) => f32::from_le_bytes(b[..4].try_into().expect("4 bytes")) as f64,
                (true, _) => f64::from_le_bytes(b),
                (false, w) if signed => {
                    let shift = 64 - 8 * w as u32;
                    ((i64::from_le_bytes(b) << shift) >> shift) as f64
                }
                (false, _) => u64::from_le_bytes(b) as f64,
            }
        })
        .collect();
    match shape.as_slice() {
        [n] => Ok(vec![values[..*n].to_vec()]),
        [t, d] => Ok(values
            .chunks(*d.max(&1))
            .take(*t)
            .map(<[f64]>::to_vec)
            .collect()),
        other => Err(ActionsError::Shape(other.to_vec())),
    }
}

/// A short name of a value's kind, for error messages.
pub fn kind_of(v: &Value) -> &'static str {
    match v {
        Value::Nil => "nil",
        Value::Boolean(_) => "a boolean",
        Value::Integer(_) => "an integer",
        Value::F32(_) | Value::F64(_) => "a float",
        Value::String(_) => "a string",
        Value::Binary(_) => "binary data",
        Value::Array(_) => "an array",
        Value::Map(_) => "a map",
        Value::Ext(..) => "an extension value",
    }
}

pub fn encode(v: &Value) -> Vec<u8> {
    let mut out = Vec::new();
    rmpv::encode::write_value(&mut out, v).expect("writing msgpack into memory");
    out
}

pub fn decode(bytes: &[u8]) -> Result<Value, DecodeError> {
    let mut r = bytes;
    let v = rmpv::decode::read_value_with_max_depth(&mut r, 64).map_err(|source| {
        DecodeError::NotMsgpack {
            len: bytes.len(),
            source,
        }
    })?;
    if !r.is_empty() {
        return Err(DecodeError::Trailing {
            rest: r.len(),
            len: bytes.len(),
        });
    }
    Ok(v)
}

/// A msgpack value as JSON (binary data summarised), for manifests.
pub fn to_json(v: &Value) -> serde_json::Value {
    use serde_json::Value as J;
    match v {
        Value::Nil => J::Null,
        Value::Boolean(b) => J::Bool(*b),
        Value::Integer(i) => i
            .as_i64()
            .map(J::from)
            .or_else(|| i.as_u64().map(J::from))
            .unwrap_or(J::Null),
        Value::F32(f) => J::from(*f as f64),
        Value::F64(f) => J::from(*f),
        Value::String(s) => J::String(s.as_str().unwrap_or("<not utf-8>").to_string()),
        Value::Binary(b) => J::String(format!("<{} bytes>", b.len())),
        Value::Array(xs) => J::Array(xs.iter().map(to_json).collect()),
        Value::Map(kv) => J::Object(
            kv.iter()
                .map(|(k, v)| {
                    let k = match k {
                        Value::String(s) => s.as_str().unwrap_or("?").to_string(),
                        Value::Binary(b) => String::from_utf8_lossy(b).into_owned(),
                        other => format!("{other}"),
                    };
                    (k, to_json(v))
                })
                .collect(),
        ),
        Value::Ext(..) => J::String("<extension>".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_round_trip_in_both_dialects_and_both_float_widths() {
        for keys in [Keys::Binary, Keys::Text] {
            for dtype in [StateDtype::Float32, StateDtype::Float64] {
                let v = floats(keys, &[0.5, -1.25, 3.0], dtype);
                let back = decode(&encode(&v)).unwrap();
                assert_eq!(actions(&back).unwrap(), vec![vec![0.5, -1.25, 3.0]]);
            }
        }
        let why = |v: &Value| actions(v).unwrap_err().to_string();
        let bad = ndarray(Keys::Text, vec![0; 5], "<f4", &[2]);
        assert_eq!(
            why(&bad),
            "the array's data has 5 bytes, which is not shape [2] of `<f4`"
        );
        let huge = ndarray(Keys::Text, vec![], "<f4", &[1 << 62, 1 << 4]);
        assert!(why(&huge).contains("not shape"));
        let odd = ndarray(Keys::Text, vec![0; 16], "<c8", &[2]);
        assert_eq!(
            why(&odd),
            "the actions have dtype `<c8`, not a float or integer type"
        );
        let cube = ndarray(Keys::Text, vec![0; 4], "<f4", &[1, 1, 1]);
        assert_eq!(
            why(&cube),
            "the actions have shape [1, 1, 1]; expected (chunk, dim) or (dim,)"
        );
        assert_eq!(why(&str("x")), "the actions are a string, not an array");
        assert_eq!(
            why(&Value::Array(vec![str("x")])),
            "an action component is a string, not a number"
        );
        let big = ndarray(Keys::Binary, 1.5f64.to_be_bytes().to_vec(), ">f8", &[1, 1]);
        assert_eq!(actions(&big).unwrap(), vec![vec![1.5]]);
        // Cut short (an array of two holding one value), and a value with bytes after it.
        assert!(
            decode(&[0x92, 0x01])
                .unwrap_err()
                .to_string()
                .starts_with("not msgpack (2 bytes): ")
        );
        assert_eq!(
            decode(&[0x01, 0x02]).unwrap_err().to_string(),
            "not msgpack: 1 of its 2 bytes follow the first value"
        );
    }
}
