//! Shared by the integration tests: one sample of every message, frames built without the
//! codec's own header writer, and the spec's CRC computed bit by bit.

// Each test file uses a different part of this module.
#![allow(dead_code)]

use needle_igtl::{
    encode_frame, Extended, FrameInfo, Message, PointElement, PointList, PolyData, Position,
    Status, StatusCode, StringMessage, TextEncoding, Timestamp, Transform,
};

/// CRC-64/ECMA-182 by long division, straight from its definition (MSB first, init 0).
pub fn crc64_bitwise(bytes: &[u8]) -> u64 {
    let mut crc = 0u64;
    for &b in bytes {
        crc ^= u64::from(b) << 56;
        for _ in 0..8 {
            crc = if crc & (1 << 63) != 0 {
                (crc << 1) ^ 0x42F0_E1EB_A9EA_3693
            } else {
                crc << 1
            };
        }
    }
    crc
}

/// A frame assembled field by field as the spec's header table lays it out.
pub fn raw_frame(version: u16, type_name: &str, device: &[u8], body: &[u8]) -> Vec<u8> {
    let mut f = Vec::new();
    f.extend_from_slice(&version.to_be_bytes());
    let mut type_field = [0u8; 12];
    type_field[..type_name.len()].copy_from_slice(type_name.as_bytes());
    f.extend_from_slice(&type_field);
    let mut device_field = [0u8; 20];
    device_field[..device.len()].copy_from_slice(device);
    f.extend_from_slice(&device_field);
    f.extend_from_slice(&0x6553_F100_8000_0000u64.to_be_bytes());
    f.extend_from_slice(&(body.len() as u64).to_be_bytes());
    f.extend_from_slice(&crc64_bitwise(body).to_be_bytes());
    f.extend_from_slice(body);
    f
}

/// Big-endian bytes of floats.
pub fn be_f32s(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_be_bytes()).collect()
}

/// A rotation of `angle` radians about the unit axis `(x, y, z)` (Rodrigues), row-major.
pub fn rotation(axis: [f32; 3], angle: f32) -> [[f32; 3]; 3] {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let [x, y, z] = axis.map(|a| a / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

/// One message of every type (two of POLYDATA and STRING: with and without their options).
pub fn samples() -> Vec<Message> {
    let pose = Transform::new(rotation([1.0, 2.0, 3.0], 0.7), [1.5, -2.25, 300.0]).unwrap();
    let half = core::f32::consts::FRAC_1_SQRT_2;
    let position = Position::new([-4.0, 5.5, 120.25], [0.0, half, 0.0, half]).unwrap();
    let mut status = Status::new(StatusCode::NOT_READY);
    status.subcode = -42;
    status.error_name = "Starting".try_into().unwrap();
    status.message = "Tracker warming up".try_into().unwrap();
    let utf8 = StringMessage {
        encoding: TextEncoding::Utf8,
        text: "Nadel → Ziel".try_into().unwrap(),
    };
    let mut points = PointList::default();
    for i in 0..3 {
        let mut p = PointElement::at(&format!("F-{i}"), [i as f32, 2.0 * i as f32, -1.0]).unwrap();
        p.group = "Fiducial".try_into().unwrap();
        p.rgba = [10, 20, 30, 255];
        p.diameter = 2.5;
        p.owner = "CT".try_into().unwrap();
        points.points.push(p).unwrap();
    }
    let path: Vec<[f32; 3]> = (0..40)
        .map(|i| [0.1 * i as f32, 0.0, 2.0 * i as f32])
        .collect();
    vec![
        Message::Transform(pose),
        Message::Position(position),
        Message::Status(status),
        Message::String(StringMessage::ascii("needle at target").unwrap()),
        Message::String(utf8),
        Message::Point(points),
        Message::PolyData(PolyData::polyline(&path).unwrap()),
        Message::PolyData(PolyData::new(&path[..3], &[]).unwrap()),
    ]
}

/// v1/v2 frame info.
pub fn info_v1(device: &str) -> FrameInfo {
    let mut info = FrameInfo::new(device).unwrap();
    info.timestamp = Timestamp::from_secs_nanos(1_700_000_000, 123_456_789);
    info
}

/// v3 frame info with a message id and two metadata entries.
pub fn info_v3(device: &str, id: u32) -> FrameInfo {
    let mut info = info_v1(device);
    let mut ext = Extended {
        message_id: id,
        ..Extended::default()
    };
    ext.metadata
        .insert("TransformStatus", TextEncoding::UsAscii, "OK")
        .unwrap();
    ext.metadata
        .insert("Operator", TextEncoding::Utf8, "Dr. Müller")
        .unwrap();
    info.extended = Some(ext);
    info
}

/// `message` encoded as one frame.
pub fn encoded(info: &FrameInfo, message: &Message) -> Vec<u8> {
    let mut buf = vec![0u8; 16 * 1024];
    let n = encode_frame(info, message, &mut buf).unwrap();
    buf.truncate(n);
    buf
}

/// A tiny xorshift64 generator: a fixed seed gives the same inputs on every run.
pub struct XorShift(pub u64);

impl XorShift {
    pub fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }

    /// Uniform-ish in `0..n` (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}
