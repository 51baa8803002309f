//! The ROS 2 messages read with fixed serde structs, and their CDR decoding.

use serde::{de::DeserializeOwned, Deserialize, Serialize};

/// `builtin_interfaces/msg/Time`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds, `0..1e9`.
    pub nanosec: u32,
}

impl Time {
    /// Nanoseconds since the epoch.
    pub fn nanos(&self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }

    /// Whether this is the zero stamp (a publisher that does not stamp its messages).
    pub fn is_zero(&self) -> bool {
        self.sec == 0 && self.nanosec == 0
    }
}

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// The stamp.
    pub stamp: Time,
    /// The frame.
    pub frame_id: String,
}

/// `sensor_msgs/msg/JointState`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointState {
    /// Header.
    pub header: Header,
    /// Joint names.
    pub name: Vec<String>,
    /// Positions (rad or m).
    pub position: Vec<f64>,
    /// Velocities.
    pub velocity: Vec<f64>,
    /// Efforts (torque, or motor current on some drivers).
    pub effort: Vec<f64>,
}

/// `geometry_msgs/msg/Vector3`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `geometry_msgs/msg/Wrench`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Wrench {
    /// Force (N).
    pub force: Vector3,
    /// Torque (Nm).
    pub torque: Vector3,
}

/// `geometry_msgs/msg/WrenchStamped`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WrenchStamped {
    /// Header.
    pub header: Header,
    /// The wrench.
    pub wrench: Wrench,
}

/// `std_msgs/msg/MultiArrayDimension`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MultiArrayDimension {
    /// Label.
    pub label: String,
    /// Size.
    pub size: u32,
    /// Stride.
    pub stride: u32,
}

/// `std_msgs/msg/MultiArrayLayout`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MultiArrayLayout {
    /// Dimensions.
    pub dim: Vec<MultiArrayDimension>,
    /// Offset of the first element in `data`.
    pub data_offset: u32,
}

/// `std_msgs/msg/Float64MultiArray` (no header: stamped with the log time).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Float64MultiArray {
    /// Layout.
    pub layout: MultiArrayLayout,
    /// Data.
    pub data: Vec<f64>,
}

impl Float64MultiArray {
    /// The elements from `layout.data_offset` on, or an error when the offset is past the
    /// end.
    pub fn values(&self) -> Result<&[f64], String> {
        let offset = self.layout.data_offset as usize;
        self.data.get(offset..).ok_or_else(|| {
            format!(
                "layout.data_offset {offset} is past the {} data elements",
                self.data.len()
            )
        })
    }
}

/// Splits a CDR payload into its byte order (`true`: little endian) and body, checking the
/// 4-byte encapsulation header (plain CDR only).
pub fn encapsulation(payload: &[u8]) -> Result<(bool, &[u8]), String> {
    if payload.len() < 4 {
        return Err(format!(
            "{} bytes, shorter than the 4-byte CDR header",
            payload.len()
        ));
    }
    let little = match (payload[0], payload[1]) {
        (0, 0) => false,
        (0, 1) => true,
        (a, b) => {
            return Err(format!(
                "CDR representation {a:#04x}{b:02x} is not plain CDR (0x0000 or 0x0001)"
            ))
        }
    };
    Ok((little, &payload[4..]))
}

/// Decodes a CDR payload (with its 4-byte header) into `T`. More than 3 bytes left over
/// (CDR pads to 4) means the payload is not a `T`: an error, as is running out of bytes.
pub fn decode<T: DeserializeOwned>(payload: &[u8]) -> Result<T, String> {
    use cdr_encoding::from_bytes;
    let (little, body) = encapsulation(payload)?;
    let (value, used) = if little {
        from_bytes::<T, byteorder_le::LE>(body)
    } else {
        from_bytes::<T, byteorder_le::BE>(body)
    }
    .map_err(|e| format!("CDR decoding failed: {e}"))?;
    let left = body.len().saturating_sub(used);
    if left > 3 {
        return Err(format!(
            "{left} bytes left after the message: not this message type"
        ));
    }
    Ok(value)
}

/// Encodes a message as little-endian CDR with its header (tests write bags with it).
pub fn encode<T: Serialize>(value: &T) -> Result<Vec<u8>, String> {
    let mut out = vec![0u8, 1, 0, 0];
    let body = cdr_encoding::to_vec::<T, byteorder_le::LE>(value).map_err(|e| e.to_string())?;
    out.extend_from_slice(&body);
    Ok(out)
}

/// The byte orders of `cdr-encoding` (from `byteorder`).
mod byteorder_le {
    pub use byteorder::{BigEndian as BE, LittleEndian as LE};
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joint_state_round_trip_and_wrong_type() {
        let js = JointState {
            header: Header {
                stamp: Time { sec: 5, nanosec: 7 },
                frame_id: "base".into(),
            },
            name: vec!["a".into(), "bb".into()],
            position: vec![1.0, 2.0],
            velocity: vec![],
            effort: vec![3.0, -4.5],
        };
        let bytes = encode(&js).unwrap();
        assert_eq!(decode::<JointState>(&bytes).unwrap(), js);
        // A JointState is not a WrenchStamped (bytes left over), and a cut payload fails.
        assert!(decode::<WrenchStamped>(&bytes).is_err());
        assert!(decode::<JointState>(&bytes[..bytes.len() - 9]).is_err());
        assert!(decode::<JointState>(&bytes[..3]).is_err());
    }

    #[test]
    fn multi_array_offset() {
        let m = Float64MultiArray {
            layout: MultiArrayLayout {
                dim: vec![],
                data_offset: 1,
            },
            data: vec![9.0, 1.0, 2.0],
        };
        let back: Float64MultiArray = decode(&encode(&m).unwrap()).unwrap();
        assert_eq!(back.values().unwrap(), &[1.0, 2.0]);
        let bad = Float64MultiArray {
            layout: MultiArrayLayout {
                dim: vec![],
                data_offset: 4,
            },
            data: vec![1.0],
        };
        assert!(bad.values().is_err());
    }
}
