//! JSON for Foxglove from nauta's self-describing schema records
//! ([`crate::schema`]): a JSON Schema per type and the JSON of each bincode
//! payload, both driven by the recorded field list, so that a recording made
//! by another build of nauta converts as long as its schemas are in the file.
//!
//! Mapping of the Rust types the schema names:
//! - `f32`, `f64` → `number`; integers → `integer` with the type's `minimum`
//!   and `maximum`; `bool` → `boolean`;
//! - `[T; N]` → `array` with `minItems = maxItems = N`; nested arrays
//!   (`[[f64; 4]; 4]`) are flattened row-major into one array of the product's
//!   length (Foxglove's JSON Schema reader takes no arrays of arrays);
//! - `[u8; N]` (nauta's NUL-padded names) → `string` of at most N characters
//!   (the UTF-8 up to the first NUL);
//! - `Header` → an object with the header's fields.
//!
//! JSON has no NaN or infinity: a float field holding one is left out of that
//! message (a whole array if any element is not finite) and counted; float
//! fields are therefore not `required`, every other field is. Every object
//! has `additionalProperties: false`.

use std::io::Write as _;

use serde_json::{Map, Value, json};

use crate::schema::Schema;

/// A fixed-width wire type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Prim {
    /// `bool`, one byte 0 or 1.
    Bool,
    /// `u8`.
    U8,
    /// `u16`.
    U16,
    /// `u32`.
    U32,
    /// `u64`.
    U64,
    /// `i8`.
    I8,
    /// `i16`.
    I16,
    /// `i32`.
    I32,
    /// `i64`.
    I64,
    /// `f32`.
    F32,
    /// `f64`.
    F64,
}

impl Prim {
    fn parse(s: &str) -> Option<Prim> {
        Some(match s {
            "bool" => Prim::Bool,
            "u8" => Prim::U8,
            "u16" => Prim::U16,
            "u32" => Prim::U32,
            "u64" => Prim::U64,
            "i8" => Prim::I8,
            "i16" => Prim::I16,
            "i32" => Prim::I32,
            "i64" => Prim::I64,
            "f32" => Prim::F32,
            "f64" => Prim::F64,
            _ => return None,
        })
    }

    /// Bytes on the wire.
    pub fn size(self) -> usize {
        match self {
            Prim::Bool | Prim::U8 | Prim::I8 => 1,
            Prim::U16 | Prim::I16 => 2,
            Prim::U32 | Prim::I32 | Prim::F32 => 4,
            Prim::U64 | Prim::I64 | Prim::F64 => 8,
        }
    }

    /// True for `f32` and `f64`.
    pub fn is_float(self) -> bool {
        matches!(self, Prim::F32 | Prim::F64)
    }

    fn schema(self) -> Value {
        match self {
            Prim::Bool => json!({"type": "boolean"}),
            Prim::F32 | Prim::F64 => json!({"type": "number"}),
            Prim::U8 => json!({"type": "integer", "minimum": 0, "maximum": u8::MAX}),
            Prim::U16 => json!({"type": "integer", "minimum": 0, "maximum": u16::MAX}),
            Prim::U32 => json!({"type": "integer", "minimum": 0, "maximum": u32::MAX}),
            Prim::U64 => json!({"type": "integer", "minimum": 0, "maximum": u64::MAX}),
            Prim::I8 => json!({"type": "integer", "minimum": i8::MIN, "maximum": i8::MAX}),
            Prim::I16 => json!({"type": "integer", "minimum": i16::MIN, "maximum": i16::MAX}),
            Prim::I32 => json!({"type": "integer", "minimum": i32::MIN, "maximum": i32::MAX}),
            Prim::I64 => json!({"type": "integer", "minimum": i64::MIN, "maximum": i64::MAX}),
        }
    }
}

/// How a field is laid out and exported.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FieldType {
    /// One number or bool.
    Scalar(Prim),
    /// A fixed array (`dims` outermost first), exported flat.
    Array {
        /// Element type.
        prim: Prim,
        /// Lengths, outermost first.
        dims: Vec<usize>,
    },
    /// `[u8; N]`: NUL-padded text.
    Text(usize),
    /// The common header.
    Header,
}

/// One field of a [`Layout`].
#[derive(Debug, Clone)]
pub struct FieldLayout {
    /// Name (with its unit).
    pub name: String,
    /// Documentation.
    pub doc: String,
    /// The Rust type as recorded.
    pub rust_type: String,
    /// Layout.
    pub ty: FieldType,
}

/// The wire layout of a type, from its schema record.
#[derive(Debug, Clone)]
pub struct Layout {
    /// Pinned type name.
    pub type_name: String,
    /// Fields in wire order.
    pub fields: Vec<FieldLayout>,
    /// Header fields in wire order.
    pub header: Vec<(String, String, Prim)>,
    /// Encoded size, bytes.
    pub wire_bytes: usize,
}

/// A schema that cannot be turned into a layout.
#[derive(Debug, thiserror::Error)]
pub enum LayoutError {
    /// A field's type is not one of the fixed-width types above.
    #[error("field {field}: unsupported type {ty:?}")]
    UnsupportedType {
        /// Field name.
        field: String,
        /// Its recorded type.
        ty: String,
    },
    /// An array too large to be a nauta message.
    #[error("field {0}: array too large")]
    TooLarge(String),
}

/// A payload that does not match its layout.
#[derive(Debug, thiserror::Error)]
pub enum JsonDecodeError {
    /// Wrong size.
    #[error("the payload has {got} bytes, its schema needs {want}")]
    Length {
        /// Payload bytes.
        got: usize,
        /// Layout bytes.
        want: usize,
    },
    /// A `bool` byte other than 0 or 1.
    #[error("field {field}: byte {value} is not a bool")]
    BadBool {
        /// Field name.
        field: String,
        /// The byte.
        value: u8,
    },
}

/// Most elements a field may have.
const MAX_ELEMENTS: usize = 1 << 16;

/// `[T; N]` nesting of a recorded type: the element and the lengths, outermost first.
fn parse_type(s: &str) -> Option<(Prim, Vec<usize>)> {
    let s = s.trim();
    match s.strip_prefix('[').and_then(|x| x.strip_suffix(']')) {
        Some(inner) => {
            // The last `;` is the outermost one: inner arrays come before it.
            let semi = inner.rfind(';')?;
            let n: usize = inner[semi + 1..].trim().parse().ok()?;
            let (prim, mut dims) = parse_type(&inner[..semi])?;
            dims.insert(0, n);
            Some((prim, dims))
        }
        None => Some((Prim::parse(s)?, Vec::new())),
    }
}

impl Layout {
    /// The layout of `schema`.
    pub fn new(schema: &Schema) -> Result<Layout, LayoutError> {
        let mut header = Vec::new();
        for f in &schema.header {
            match parse_type(&f.ty) {
                Some((p, dims)) if dims.is_empty() => {
                    header.push((f.name.clone(), f.doc.clone(), p))
                }
                _ => {
                    return Err(LayoutError::UnsupportedType {
                        field: format!("header.{}", f.name),
                        ty: f.ty.clone(),
                    });
                }
            }
        }
        let header_bytes: usize = header.iter().map(|(_, _, p)| p.size()).sum();
        let mut fields = Vec::new();
        let mut wire_bytes = 0usize;
        for f in &schema.fields {
            let unsupported = || LayoutError::UnsupportedType {
                field: f.name.clone(),
                ty: f.ty.clone(),
            };
            let (ty, bytes) = if f.ty.trim() == "Header" {
                if header.is_empty() {
                    return Err(unsupported());
                }
                (FieldType::Header, header_bytes)
            } else {
                let (prim, dims) = parse_type(&f.ty).ok_or_else(unsupported)?;
                let count = dims
                    .iter()
                    .try_fold(1usize, |a, &n| a.checked_mul(n))
                    .filter(|&c| c <= MAX_ELEMENTS)
                    .ok_or_else(|| LayoutError::TooLarge(f.name.clone()))?;
                let ty = match (prim, dims.len()) {
                    (_, 0) => FieldType::Scalar(prim),
                    (Prim::U8, 1) => FieldType::Text(count),
                    _ => FieldType::Array { prim, dims },
                };
                (ty, count * prim.size())
            };
            wire_bytes += bytes;
            fields.push(FieldLayout {
                name: f.name.clone(),
                doc: f.doc.clone(),
                rust_type: f.ty.clone(),
                ty,
            });
        }
        Ok(Layout {
            type_name: schema.type_name.clone(),
            fields,
            header,
            wire_bytes,
        })
    }

    /// The JSON Schema of this type's messages.
    pub fn json_schema(&self) -> Value {
        let mut props = Map::new();
        let mut required = Vec::new();
        for f in &self.fields {
            let mut s = match &f.ty {
                FieldType::Scalar(p) => p.schema(),
                FieldType::Array { prim, dims } => {
                    let n: usize = dims.iter().product();
                    json!({"type": "array", "items": prim.schema(), "minItems": n, "maxItems": n})
                }
                FieldType::Text(n) => json!({"type": "string", "maxLength": n}),
                FieldType::Header => {
                    let mut hp = Map::new();
                    for (name, doc, p) in &self.header {
                        let mut s = p.schema();
                        s["description"] = json!(doc);
                        hp.insert(name.clone(), s);
                    }
                    let names: Vec<&String> = self.header.iter().map(|(n, _, _)| n).collect();
                    json!({
                        "type": "object",
                        "title": "nauta.Header",
                        "properties": hp,
                        "required": names,
                        "additionalProperties": false,
                    })
                }
            };
            let mut doc = f.doc.clone();
            match &f.ty {
                FieldType::Array { dims, .. } if dims.len() > 1 => {
                    doc.push_str(&format!(" (Flattened row-major from {}.)", f.rust_type));
                }
                FieldType::Text(_) => {
                    doc.push_str(&format!(
                        " ({} on the wire: UTF-8 up to the first NUL.)",
                        f.rust_type
                    ));
                }
                _ => {}
            }
            s["description"] = json!(doc.trim());
            let float = matches!(
                &f.ty,
                FieldType::Scalar(p) | FieldType::Array { prim: p, .. } if p.is_float()
            );
            if !float {
                required.push(f.name.clone());
            }
            props.insert(f.name.clone(), s);
        }
        json!({
            "$schema": "https://json-schema.org/draft/2020-12/schema",
            "title": self.type_name,
            "description": format!(
                "{}: a nauta message as JSON (nauta export). A float field holding a non-finite \
                 number (JSON has none) is left out of that message.",
                self.type_name
            ),
            "type": "object",
            "properties": props,
            "required": required,
            "additionalProperties": false,
        })
    }

    /// Appends the JSON object of the payload `data` to `out`; returns how many
    /// fields were left out for holding a non-finite number. `out` is
    /// unchanged on error.
    pub fn to_json(&self, data: &[u8], out: &mut Vec<u8>) -> Result<u64, JsonDecodeError> {
        if data.len() != self.wire_bytes {
            return Err(JsonDecodeError::Length {
                got: data.len(),
                want: self.wire_bytes,
            });
        }
        let start = out.len();
        match self.write_json(data, out) {
            Ok(n) => Ok(n),
            Err(e) => {
                out.truncate(start);
                Err(e)
            }
        }
    }

    fn write_json(&self, data: &[u8], out: &mut Vec<u8>) -> Result<u64, JsonDecodeError> {
        let mut r = Cursor { data, at: 0 };
        let mut left_out = 0u64;
        let mut first = true;
        out.push(b'{');
        for f in &self.fields {
            match &f.ty {
                FieldType::Header => {
                    key(out, &mut first, &f.name);
                    out.push(b'{');
                    for (i, (name, _, p)) in self.header.iter().enumerate() {
                        if i > 0 {
                            out.push(b',');
                        }
                        string(out, name);
                        out.push(b':');
                        let v = r.read(*p, name)?;
                        v.write(out);
                    }
                    out.push(b'}');
                }
                FieldType::Scalar(p) => {
                    let v = r.read(*p, &f.name)?;
                    if v.is_finite() {
                        key(out, &mut first, &f.name);
                        v.write(out);
                    } else {
                        left_out += 1;
                    }
                }
                FieldType::Array { prim, dims } => {
                    let n: usize = dims.iter().product();
                    let mut values = Vec::with_capacity(n);
                    for _ in 0..n {
                        values.push(r.read(*prim, &f.name)?);
                    }
                    if values.iter().all(Num::is_finite) {
                        key(out, &mut first, &f.name);
                        out.push(b'[');
                        for (i, v) in values.iter().enumerate() {
                            if i > 0 {
                                out.push(b',');
                            }
                            v.write(out);
                        }
                        out.push(b']');
                    } else {
                        left_out += 1;
                    }
                }
                FieldType::Text(n) => {
                    let bytes = r.take(*n);
                    key(out, &mut first, &f.name);
                    string(out, &nauta_messages::fixed_str(bytes));
                }
            }
        }
        out.push(b'}');
        Ok(left_out)
    }
}

fn string(out: &mut Vec<u8>, s: &str) {
    // Writing a string to a Vec cannot fail.
    let _ = serde_json::to_writer(&mut *out, s);
}

fn key(out: &mut Vec<u8>, first: &mut bool, name: &str) {
    if !*first {
        out.push(b',');
    }
    *first = false;
    string(out, name);
    out.push(b':');
}

#[derive(Debug, Clone, Copy)]
enum Num {
    Bool(bool),
    U(u64),
    I(i64),
    F32(f32),
    F64(f64),
}

impl Num {
    fn is_finite(&self) -> bool {
        match self {
            Num::F32(x) => x.is_finite(),
            Num::F64(x) => x.is_finite(),
            _ => true,
        }
    }

    fn write(&self, out: &mut Vec<u8>) {
        // Writes to a Vec cannot fail; non-finite floats are never written.
        let _ = match self {
            Num::Bool(b) => out.write_all(if *b { b"true" } else { b"false" }),
            Num::U(v) => write!(out, "{v}"),
            Num::I(v) => write!(out, "{v}"),
            Num::F32(x) => serde_json::to_writer(&mut *out, x).map_err(std::io::Error::other),
            Num::F64(x) => serde_json::to_writer(&mut *out, x).map_err(std::io::Error::other),
        };
    }
}

struct Cursor<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    /// The next `n` bytes (the layout's size was checked against the payload).
    fn take(&mut self, n: usize) -> &'a [u8] {
        let end = (self.at + n).min(self.data.len());
        let b = &self.data[self.at.min(end)..end];
        self.at = end;
        b
    }

    fn le<const N: usize>(&mut self) -> [u8; N] {
        let mut a = [0u8; N];
        let b = self.take(N);
        a[..b.len()].copy_from_slice(b);
        a
    }

    fn read(&mut self, p: Prim, field: &str) -> Result<Num, JsonDecodeError> {
        Ok(match p {
            Prim::Bool => match self.le::<1>()[0] {
                0 => Num::Bool(false),
                1 => Num::Bool(true),
                value => {
                    return Err(JsonDecodeError::BadBool {
                        field: field.to_owned(),
                        value,
                    });
                }
            },
            Prim::U8 => Num::U(u64::from(self.le::<1>()[0])),
            Prim::U16 => Num::U(u64::from(u16::from_le_bytes(self.le()))),
            Prim::U32 => Num::U(u64::from(u32::from_le_bytes(self.le()))),
            Prim::U64 => Num::U(u64::from_le_bytes(self.le())),
            Prim::I8 => Num::I(i64::from(i8::from_le_bytes(self.le()))),
            Prim::I16 => Num::I(i64::from(i16::from_le_bytes(self.le()))),
            Prim::I32 => Num::I(i64::from(i32::from_le_bytes(self.le()))),
            Prim::I64 => Num::I(i64::from_le_bytes(self.le())),
            Prim::F32 => Num::F32(f32::from_le_bytes(self.le())),
            Prim::F64 => Num::F64(f64::from_le_bytes(self.le())),
        })
    }
}

#[cfg(test)]
mod tests {
    use nauta_messages::*;

    use super::*;

    /// The serde JSON of a message, reshaped as the export writes it: nested
    /// arrays flat, `[u8; N]` as text.
    fn expected(layout: &Layout, serde: Value) -> Value {
        let mut obj = match serde {
            Value::Object(m) => m,
            other => panic!("not an object: {other}"),
        };
        for f in &layout.fields {
            let v = obj.remove(&f.name).expect("field");
            let v = match &f.ty {
                FieldType::Array { dims, .. } if dims.len() > 1 => {
                    fn flat(v: &Value, out: &mut Vec<Value>) {
                        match v {
                            Value::Array(a) => a.iter().for_each(|x| flat(x, out)),
                            x => out.push(x.clone()),
                        }
                    }
                    let mut out = Vec::new();
                    flat(&v, &mut out);
                    Value::Array(out)
                }
                FieldType::Text(_) => {
                    let bytes: Vec<u8> = v
                        .as_array()
                        .expect("bytes")
                        .iter()
                        .map(|b| b.as_u64().expect("byte") as u8)
                        .collect();
                    json!(fixed_str(&bytes))
                }
                _ => v,
            };
            obj.insert(f.name.clone(), v);
        }
        Value::Object(obj)
    }

    fn check<M: Message>(m: &M) -> Value {
        let schema = crate::schema::Schema::of(&TypeInfo::of::<M>());
        let layout = Layout::new(&schema).expect("layout");
        let bytes = codec::encode(m).expect("encode");
        assert_eq!(bytes.len(), layout.wire_bytes, "{}", M::TYPE_NAME);
        let mut out = Vec::new();
        assert_eq!(layout.to_json(&bytes, &mut out).expect("json"), 0);
        let got: Value = serde_json::from_slice(&out).expect("valid JSON");
        assert_eq!(
            got,
            expected(&layout, serde_json::to_value(m).expect("serde")),
            "{}",
            M::TYPE_NAME
        );
        // Every key is in the schema, every required key is present.
        let js = layout.json_schema();
        let props = js["properties"].as_object().expect("properties");
        for k in got.as_object().expect("object").keys() {
            assert!(props.contains_key(k), "{k} not in the schema");
        }
        for r in js["required"].as_array().expect("required") {
            assert!(got.get(r.as_str().expect("name")).is_some(), "{r} missing");
        }
        got
    }

    #[test]
    fn every_registered_type_converts_like_its_serde_json() {
        struct All;
        impl MessageVisitor for All {
            fn visit<M: Message>(&mut self) {
                let mut m = M::default();
                *m.header_mut() = Header::new(123_456_789, 42, Role::Ains, 3);
                check(&m);
            }
        }
        registry::visit_all(&mut All);
    }

    #[test]
    fn matrices_are_flattened_names_are_text_and_non_finite_fields_left_out() {
        let mut lbl = LblSolution {
            header: Header::new(5, 1, Role::Lbl, 0),
            x_m: 12.5,
            ..Default::default()
        };
        for (i, row) in lbl.p.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = (i * 4 + j) as f64 * 0.5;
            }
        }
        let got = check(&lbl);
        assert_eq!(got["p"][6], json!(3.0));
        assert_eq!(got["p"].as_array().map(Vec::len), Some(16));
        assert_eq!(got["header"]["source"], json!(Role::Lbl as u32));

        let ev = RunEvent {
            process: to_fixed_str("attitude"),
            variant: to_fixed_str("pf\"x"),
            exit_code: -9,
            ..Default::default()
        };
        let got = check(&ev);
        assert_eq!(got["process"], json!("attitude"));
        assert_eq!(got["variant"], json!("pf\"x"));
        assert_eq!(got["exit_code"], json!(-9));

        let nav = NavSolution {
            lat_rad: f64::NAN,
            vel_ned_m_s: [1.0, f64::INFINITY, 0.0],
            depth_m: 1e-300,
            ..Default::default()
        };
        let layout = Layout::new(&crate::schema::Schema::of(&TypeInfo::of::<NavSolution>()))
            .expect("layout");
        let mut out = Vec::new();
        let n = layout
            .to_json(&codec::encode(&nav).expect("encode"), &mut out)
            .expect("json");
        assert_eq!(n, 2);
        let got: Value = serde_json::from_slice(&out).expect("valid JSON");
        assert!(got.get("lat_rad").is_none() && got.get("vel_ned_m_s").is_none());
        assert_eq!(got["depth_m"], json!(1e-300));
        assert_eq!(got["lon_rad"], json!(0.0));
    }

    #[test]
    fn bad_payloads_and_schemas_are_errors() {
        let layout = Layout::new(&crate::schema::Schema::of(&TypeInfo::of::<DepthSample>()))
            .expect("layout");
        let mut out = b"x".to_vec();
        assert!(matches!(
            layout.to_json(&[0u8; 39], &mut out),
            Err(JsonDecodeError::Length { got: 39, want: 40 })
        ));
        assert_eq!(out, b"x");
        let mut s = crate::schema::Schema::of(&TypeInfo::of::<DepthSample>());
        s.fields[1].ty = "Vec<f64>".to_owned();
        assert!(Layout::new(&s).is_err());
        s.fields[1].ty = "[[f64; 100000]; 100000]".to_owned();
        assert!(matches!(Layout::new(&s), Err(LayoutError::TooLarge(_))));
        s.fields[1].ty = "bool".to_owned();
        s.fields.push(crate::schema::Field {
            name: "pad".to_owned(),
            ty: "[u8; 7]".to_owned(),
            doc: String::new(),
        });
        let layout = Layout::new(&s).expect("layout");
        let mut data = vec![0u8; 40];
        data[32] = 2;
        assert!(matches!(
            layout.to_json(&data, &mut Vec::new()),
            Err(JsonDecodeError::BadBool { value: 2, .. })
        ));
        data[32] = 1;
        let mut out = Vec::new();
        layout.to_json(&data, &mut out).expect("json");
        let got: Value = serde_json::from_slice(&out).expect("valid JSON");
        assert_eq!(got["depth_m"], json!(true));
        assert_eq!(got["pad"], json!(""));
    }

    #[test]
    fn nested_types_parse() {
        assert_eq!(parse_type("[[f64; 4]; 2]"), Some((Prim::F64, vec![2, 4])));
        assert_eq!(parse_type(" u32 "), Some((Prim::U32, vec![])));
        assert_eq!(parse_type("[f64;3]"), Some((Prim::F64, vec![3])));
        assert_eq!(parse_type("[f64; x]"), None);
        assert_eq!(parse_type("String"), None);
    }
}
