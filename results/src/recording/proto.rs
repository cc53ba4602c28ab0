//! The recording's binary channels in protobuf (what Foxglove and the `mcap` tools decode from a
//! channel's schema, a serialized `FileDescriptorSet`): camera frames as `foxglove.CompressedImage`
//! (PNG, lossless) and MuJoCo's state as `autobio.PhysicsState`. A small hand-written encoder and
//! decoder for exactly these messages; no code generation.

/// `mj_getState` spec recorded on `/physics/state`: `mjSTATE_INTEGRATION`, everything
/// `mj_step` reads (time, qpos, qvel, act, history, warm start, ctrl, applied forces, equality
/// switches, mocap poses, user data, plugin state).
pub const STATE_SPEC: u32 = 16383;

const VARINT: u64 = 0;
const FIXED64: u64 = 1;
const LEN: u64 = 2;

fn varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

fn tag(out: &mut Vec<u8>, field: u64, wire: u64) {
    varint(out, (field << 3) | wire);
}

fn bytes(out: &mut Vec<u8>, field: u64, b: &[u8]) {
    tag(out, field, LEN);
    varint(out, b.len() as u64);
    out.extend_from_slice(b);
}

fn uint(out: &mut Vec<u8>, field: u64, v: u64) {
    if v != 0 {
        tag(out, field, VARINT);
        varint(out, v);
    }
}

fn timestamp(ns: u64) -> Vec<u8> {
    let mut t = Vec::new();
    uint(&mut t, 1, ns / 1_000_000_000);
    uint(&mut t, 2, ns % 1_000_000_000);
    t
}

/// `foxglove.CompressedImage`: timestamp = 1, data = 2, format = 3, frame_id = 4.
pub fn compressed_image(ns: u64, frame_id: &str, format: &str, data: &[u8]) -> Vec<u8> {
    let mut m = Vec::with_capacity(data.len() + 64);
    bytes(&mut m, 1, &timestamp(ns));
    bytes(&mut m, 2, data);
    bytes(&mut m, 3, format.as_bytes());
    bytes(&mut m, 4, frame_id.as_bytes());
    m
}

/// `autobio.PhysicsState`: timestamp = 1, spec = 2, state = 3 (packed doubles).
pub fn physics_state(ns: u64, spec: u32, state: &[f64]) -> Vec<u8> {
    let mut m = Vec::with_capacity(state.len() * 8 + 32);
    bytes(&mut m, 1, &timestamp(ns));
    uint(&mut m, 2, u64::from(spec));
    let packed: Vec<u8> = state.iter().flat_map(|v| v.to_le_bytes()).collect();
    bytes(&mut m, 3, &packed);
    m
}

/// A decoded field: a varint, a fixed 64-bit value or a length-delimited slice.
#[derive(Debug, PartialEq)]
pub enum Field<'a> {
    Varint(u64),
    Fixed64(u64),
    Bytes(&'a [u8]),
}

fn read_varint(b: &[u8], at: &mut usize) -> Option<u64> {
    let mut v = 0u64;
    for shift in (0..64).step_by(7) {
        let byte = *b.get(*at)?;
        *at += 1;
        v |= u64::from(byte & 0x7f) << shift;
        if byte < 0x80 {
            return Some(v);
        }
    }
    None
}

/// Every field of one message, in order; `None` when the bytes are not protobuf of the wire types
/// used here.
pub fn fields(b: &[u8]) -> Option<Vec<(u64, Field<'_>)>> {
    let mut at = 0;
    let mut out = Vec::new();
    while at < b.len() {
        let key = read_varint(b, &mut at)?;
        let field = match key & 7 {
            VARINT => Field::Varint(read_varint(b, &mut at)?),
            FIXED64 => {
                let v = b.get(at..at + 8)?;
                at += 8;
                Field::Fixed64(u64::from_le_bytes(v.try_into().ok()?))
            }
            LEN => {
                let n = usize::try_from(read_varint(b, &mut at)?).ok()?;
                let v = b.get(at..at.checked_add(n)?)?;
                at += n;
                Field::Bytes(v)
            }
            _ => return None,
        };
        out.push((key >> 3, field));
    }
    Some(out)
}

/// The `data` of a `foxglove.CompressedImage`.
pub fn image_data(b: &[u8]) -> Option<&[u8]> {
    fields(b)?.into_iter().find_map(|(f, v)| match (f, v) {
        (2, Field::Bytes(d)) => Some(d),
        _ => None,
    })
}

/// The spec and values of an `autobio.PhysicsState`.
pub fn state_values(b: &[u8]) -> Option<(u32, Vec<f64>)> {
    let mut spec = 0;
    let mut state = Vec::new();
    for (f, v) in fields(b)? {
        match (f, v) {
            (2, Field::Varint(s)) => spec = u32::try_from(s).ok()?,
            (3, Field::Bytes(d)) if d.len() % 8 == 0 => {
                state = d
                    .chunks_exact(8)
                    .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                    .collect();
            }
            (3, Field::Fixed64(v)) => state.push(f64::from_bits(v)),
            _ => {}
        }
    }
    Some((spec, state))
}

// --- Schemas: FileDescriptorSet { file = 1 } of FileDescriptorProto { name = 1, package = 2,
// dependency = 3, message_type = 4, syntax = 12 }, DescriptorProto { name = 1, field = 2 },
// FieldDescriptorProto { name = 1, number = 3, label = 4, type = 5, type_name = 6 }.

const OPTIONAL: u64 = 1;
const REPEATED: u64 = 3;
const T_DOUBLE: u64 = 1;
const T_INT64: u64 = 3;
const T_INT32: u64 = 5;
const T_STRING: u64 = 9;
const T_MESSAGE: u64 = 11;
const T_BYTES: u64 = 12;
const T_UINT32: u64 = 13;

fn field(name: &str, number: u64, label: u64, ty: u64, type_name: &str) -> Vec<u8> {
    let mut f = Vec::new();
    bytes(&mut f, 1, name.as_bytes());
    uint(&mut f, 3, number);
    uint(&mut f, 4, label);
    uint(&mut f, 5, ty);
    if !type_name.is_empty() {
        bytes(&mut f, 6, type_name.as_bytes());
    }
    f
}

fn message(name: &str, fields: &[Vec<u8>]) -> Vec<u8> {
    let mut m = Vec::new();
    bytes(&mut m, 1, name.as_bytes());
    for f in fields {
        bytes(&mut m, 2, f);
    }
    m
}

fn file(name: &str, package: &str, deps: &[&str], messages: &[Vec<u8>]) -> Vec<u8> {
    let mut f = Vec::new();
    bytes(&mut f, 1, name.as_bytes());
    bytes(&mut f, 2, package.as_bytes());
    for d in deps {
        bytes(&mut f, 3, d.as_bytes());
    }
    for m in messages {
        bytes(&mut f, 4, m);
    }
    bytes(&mut f, 12, b"proto3");
    f
}

fn timestamp_file() -> Vec<u8> {
    file(
        "google/protobuf/timestamp.proto",
        "google.protobuf",
        &[],
        &[message(
            "Timestamp",
            &[
                field("seconds", 1, OPTIONAL, T_INT64, ""),
                field("nanos", 2, OPTIONAL, T_INT32, ""),
            ],
        )],
    )
}

fn set(files: &[Vec<u8>]) -> Vec<u8> {
    let mut s = Vec::new();
    for f in files {
        bytes(&mut s, 1, f);
    }
    s
}

const TIMESTAMP: &str = ".google.protobuf.Timestamp";

/// A descriptor set for one message `package.name` in `file`, with the timestamp's file.
fn schema(file_name: &str, package: &str, name: &str, fields: &[Vec<u8>]) -> Vec<u8> {
    set(&[
        timestamp_file(),
        file(
            file_name,
            package,
            &["google/protobuf/timestamp.proto"],
            &[message(name, fields)],
        ),
    ])
}

/// The schema of `foxglove.CompressedImage`, as Foxglove defines it.
pub fn compressed_image_schema() -> Vec<u8> {
    schema(
        "foxglove/CompressedImage.proto",
        "foxglove",
        "CompressedImage",
        &[
            field("timestamp", 1, OPTIONAL, T_MESSAGE, TIMESTAMP),
            field("frame_id", 4, OPTIONAL, T_STRING, ""),
            field("data", 2, OPTIONAL, T_BYTES, ""),
            field("format", 3, OPTIONAL, T_STRING, ""),
        ],
    )
}

/// The schema of `autobio.PhysicsState`.
pub fn physics_state_schema() -> Vec<u8> {
    schema(
        "autobio/PhysicsState.proto",
        "autobio",
        "PhysicsState",
        &[
            field("timestamp", 1, OPTIONAL, T_MESSAGE, TIMESTAMP),
            field("spec", 2, OPTIONAL, T_UINT32, ""),
            field("state", 3, REPEATED, T_DOUBLE, ""),
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_decode_back() {
        let img = compressed_image(1_500_000_123, "fixed", "png", &[1, 2, 3, 255]);
        assert_eq!(image_data(&img), Some(&[1u8, 2, 3, 255][..]));
        let s = [0.0, -1.5, f64::MIN_POSITIVE, 1e300];
        let st = physics_state(7, STATE_SPEC, &s);
        assert_eq!(state_values(&st), Some((STATE_SPEC, s.to_vec())));
    }

    #[test]
    fn truncated_bytes_are_refused() {
        let img = compressed_image(1, "fixed", "png", &[9; 300]);
        assert!(fields(&img[..img.len() - 1]).is_none());
        assert!(fields(&[0xff]).is_none());
    }

    #[test]
    fn varints_cross_byte_boundaries() {
        for v in [0u64, 1, 127, 128, 300, u64::from(u32::MAX), u64::MAX] {
            let mut b = Vec::new();
            varint(&mut b, v);
            let mut at = 0;
            assert_eq!(read_varint(&b, &mut at), Some(v));
            assert_eq!(at, b.len());
        }
    }
}
