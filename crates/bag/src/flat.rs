//! Reading chosen fields of a message type that has no fixed struct here (a vendor's
//! custom message such as `lbr_fri_idl/msg/LBRState`) from the `ros2msg` definition that
//! rosbag2 embeds in the MCAP schema record.
//!
//! Only "flat" fields are understood: primitives, strings, and fixed or unbounded arrays
//! of primitives. The fields are walked in order and reading stops once the wanted ones
//! are read, so a nested type (or a `wstring`) after them does not matter; one before
//! them is an error naming it.

/// A primitive or string field type.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// A number (or bool, byte, char) of this size in bytes, and how to read it.
    Number(usize, NumberKind),
    /// A CDR string (u32 length with the NUL, then the bytes).
    Str,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum NumberKind {
    Unsigned,
    Signed,
    Float,
}

#[derive(Clone, Debug, PartialEq)]
enum Shape {
    Scalar,
    Fixed(usize),
    Sequence,
}

#[derive(Clone, Debug, PartialEq)]
struct Field {
    name: String,
    type_name: String,
    kind: Option<Kind>,
    shape: Shape,
}

/// The top-level fields of a message definition.
#[derive(Clone, Debug, PartialEq)]
pub struct FlatSchema {
    fields: Vec<Field>,
}

fn kind_of(base: &str) -> Option<Kind> {
    use NumberKind::*;
    Some(match base {
        "bool" | "byte" | "char" | "uint8" => Kind::Number(1, Unsigned),
        "int8" => Kind::Number(1, Signed),
        "uint16" => Kind::Number(2, Unsigned),
        "int16" => Kind::Number(2, Signed),
        "uint32" => Kind::Number(4, Unsigned),
        "int32" => Kind::Number(4, Signed),
        "float32" => Kind::Number(4, Float),
        "uint64" => Kind::Number(8, Unsigned),
        "int64" => Kind::Number(8, Signed),
        "float64" => Kind::Number(8, Float),
        "string" => Kind::Str,
        _ if base.starts_with("string<=") => Kind::Str,
        _ => return None,
    })
}

fn parse_field(line: &str) -> Result<Option<Field>, String> {
    let line = line.split('#').next().unwrap_or("").trim();
    if line.is_empty() {
        return Ok(None);
    }
    let mut parts = line.split_whitespace();
    let (Some(type_token), Some(name)) = (parts.next(), parts.next()) else {
        return Err(format!("cannot read the field line `{line}`"));
    };
    if name.contains('=') || parts.clone().next().is_some_and(|p| p.starts_with('=')) {
        return Ok(None); // a constant, not in the payload
    }
    let (base, shape) = match type_token.find('[') {
        None => (type_token, Shape::Scalar),
        Some(i) => {
            let inside = type_token[i + 1..].trim_end_matches(']');
            let shape = if inside.is_empty() || inside.starts_with("<=") {
                Shape::Sequence
            } else {
                Shape::Fixed(
                    inside
                        .parse()
                        .map_err(|_| format!("bad array size in `{type_token}`"))?,
                )
            };
            (&type_token[..i], shape)
        }
    };
    Ok(Some(Field {
        name: name.to_string(),
        type_name: base.to_string(),
        kind: kind_of(base),
        shape,
    }))
}

impl FlatSchema {
    /// Parses the main message of a `ros2msg` schema (the text before the first line of
    /// `=` that starts the dependencies).
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut fields = Vec::new();
        for line in text.lines() {
            if line.starts_with("===") {
                break;
            }
            if let Some(f) = parse_field(line)? {
                fields.push(f);
            }
        }
        Ok(Self { fields })
    }

    /// Whether the definition has a top-level field of this name.
    pub fn has_field(&self, name: &str) -> bool {
        self.fields.iter().any(|f| f.name == name)
    }

    /// Reads the numeric fields `wanted` (scalars give one value, arrays all of theirs)
    /// from a CDR payload with its 4-byte header, in the order of `wanted`.
    pub fn read(&self, payload: &[u8], wanted: &[&str]) -> Result<Vec<Vec<f64>>, String> {
        let (little, body) = crate::msgs::encapsulation(payload)?;
        let mut cursor = Cursor {
            body,
            pos: 0,
            little,
        };
        let mut out: Vec<Option<Vec<f64>>> = vec![None; wanted.len()];
        for field in &self.fields {
            if out.iter().all(Option::is_some) {
                break;
            }
            let slots: Vec<usize> = (0..wanted.len())
                .filter(|i| wanted[*i] == field.name)
                .collect();
            let Some(kind) = field.kind else {
                return Err(format!(
                    "field `{}` has type `{}`, which the flat decoder does not read (only primitives, strings and their arrays before the wanted fields)",
                    field.name, field.type_name
                ));
            };
            let values = cursor.field(kind, &field.shape, &field.name)?;
            for i in slots {
                match &values {
                    Some(v) => out[i] = Some(v.clone()),
                    None => return Err(format!("field `{}` is a string, not numbers", field.name)),
                }
            }
        }
        wanted
            .iter()
            .zip(out)
            .map(|(w, v)| v.ok_or_else(|| format!("no field `{w}` in the message definition")))
            .collect()
    }
}

struct Cursor<'a> {
    body: &'a [u8],
    pos: usize,
    little: bool,
}

impl Cursor<'_> {
    fn take(&mut self, n: usize, what: &str) -> Result<&[u8], String> {
        let end = self.pos.checked_add(n).filter(|e| *e <= self.body.len());
        let Some(end) = end else {
            return Err(format!(
                "payload ends inside field `{what}` ({} bytes)",
                self.body.len()
            ));
        };
        let s = &self.body[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    fn align(&mut self, to: usize, what: &str) -> Result<(), String> {
        let pad = (to - self.pos % to) % to;
        self.take(pad, what).map(|_| ())
    }

    fn u32(&mut self, what: &str) -> Result<usize, String> {
        self.align(4, what)?;
        let b: [u8; 4] = self
            .take(4, what)?
            .try_into()
            .map_err(|_| what.to_string())?;
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        } as usize)
    }

    fn number(&mut self, size: usize, kind: NumberKind, what: &str) -> Result<f64, String> {
        self.align(size, what)?;
        let little = self.little;
        let raw = self.take(size, what)?;
        let mut b = [0u8; 8];
        if little {
            b[..size].copy_from_slice(raw);
        } else {
            for (i, x) in raw.iter().rev().enumerate() {
                b[i] = *x;
            }
        }
        let bits = u64::from_le_bytes(b);
        let shift = 64 - 8 * size as u32;
        Ok(match kind {
            NumberKind::Unsigned => bits as f64,
            NumberKind::Signed => (((bits << shift) as i64) >> shift) as f64,
            NumberKind::Float if size == 4 => f64::from(f32::from_bits(bits as u32)),
            NumberKind::Float => f64::from_bits(bits),
        })
    }

    /// Reads one field: its numbers, or `None` for strings (skipped).
    fn field(&mut self, kind: Kind, shape: &Shape, what: &str) -> Result<Option<Vec<f64>>, String> {
        let count = match shape {
            Shape::Scalar => 1,
            Shape::Fixed(n) => *n,
            Shape::Sequence => self.u32(what)?,
        };
        match kind {
            Kind::Str => {
                for _ in 0..count {
                    let len = self.u32(what)?;
                    self.take(len, what)?;
                }
                Ok(None)
            }
            Kind::Number(size, nk) => {
                // The count comes from the payload: bound it by the bytes left first.
                if count.saturating_mul(size) > self.body.len().saturating_sub(self.pos) {
                    return Err(format!(
                        "field `{what}` claims {count} elements, more than the payload holds"
                    ));
                }
                (0..count)
                    .map(|_| self.number(size, nk, what))
                    .collect::<Result<Vec<_>, _>>()
                    .map(Some)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DEF: &str = "# comment\nint32 MODE=3\nfloat64 sample_time\nint8 mode\nuint32 sec\nfloat64[2] q  # two\nstring name\nint16[] seq\nfloat32 f\ngeometry_msgs/Wrench w\n================\nMSG: geometry_msgs/Wrench\nfloat64 x\n";

    fn payload() -> Vec<u8> {
        let mut b = vec![0u8, 1, 0, 0];
        b.extend(0.5f64.to_le_bytes()); // 0..8
        b.push(0xfe); // int8 -2 at 8
        b.extend([0, 0, 0]); // pad to 12
        b.extend(7u32.to_le_bytes()); // 12..16
        b.extend(1.0f64.to_le_bytes()); // 16..24
        b.extend(2.0f64.to_le_bytes()); // 24..32
        b.extend(3u32.to_le_bytes()); // "ab\0"
        b.extend(b"ab\0");
        b.push(0); // pad to 40
        b.extend(2u32.to_le_bytes());
        b.extend((-3i16).to_le_bytes());
        b.extend(4i16.to_le_bytes()); // 48
        b.extend(1.5f32.to_le_bytes());
        b
    }

    #[test]
    fn reads_wanted_fields_in_order() {
        let s = FlatSchema::parse(DEF).unwrap();
        assert!(s.has_field("q") && !s.has_field("MODE") && !s.has_field("x"));
        let v = s
            .read(&payload(), &["f", "q", "mode", "sec", "seq", "sec"])
            .unwrap();
        let sec = vec![7.0];
        assert_eq!(
            v,
            vec![
                vec![1.5],
                vec![1.0, 2.0],
                vec![-2.0],
                sec.clone(),
                vec![-3.0, 4.0],
                sec
            ]
        );
    }

    #[test]
    fn errors_name_the_field() {
        let s = FlatSchema::parse(DEF).unwrap();
        let p = payload();
        let e = s.read(&p[..30], &["q"]).unwrap_err();
        assert!(e.contains("`q`"), "{e}");
        let e = s.read(&p, &["x"]).unwrap_err();
        assert!(e.contains("geometry_msgs/Wrench"), "{e}");
        let e = s.read(&p, &["name"]).unwrap_err();
        assert!(e.contains("string"), "{e}");
    }
}
