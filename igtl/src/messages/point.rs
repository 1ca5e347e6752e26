//! POINT (`Documents/Protocol/point.md`): a list of 136-byte fiducials, each name char[64],
//! group char[32], RGBA u8×4, x y z f32 (mm), diameter f32 (mm), owner image char[20].

use crate::bytes::{Reader, Writer};
use crate::text::{fixed, put_fixed};
use crate::Error;
use heapless::{String, Vec};

/// Bytes of one point element.
pub const POINT_ELEMENT_SIZE: usize = 136;
/// Points kept per message.
pub const MAX_POINTS: usize = 16;

const NAME: usize = 64;
const GROUP: usize = 32;
const OWNER: usize = 20;

/// One fiducial.
#[derive(Debug, Clone, PartialEq)]
pub struct PointElement {
    /// Name or description.
    pub name: String<NAME>,
    /// Group, e.g. "Fiducial" or "Landmark".
    pub group: String<GROUP>,
    /// Colour, red green blue alpha.
    pub rgba: [u8; 4],
    /// Coordinates in mm.
    pub position: [f32; 3],
    /// Diameter in mm (may be 0).
    pub diameter: f32,
    /// Id of the owner image.
    pub owner: String<OWNER>,
}

impl PointElement {
    /// A named white point of diameter 0 with no group or owner.
    pub fn at(name: &str, position: [f32; 3]) -> Result<Self, Error> {
        Ok(PointElement {
            name: String::try_from(name).map_err(|_| Error::TooLarge)?,
            group: String::new(),
            rgba: [255; 4],
            position,
            diameter: 0.0,
            owner: String::new(),
        })
    }

    fn encode(&self, w: &mut Writer<'_>) -> Result<(), Error> {
        let coords = [
            self.position[0],
            self.position[1],
            self.position[2],
            self.diameter,
        ];
        if !coords.iter().all(|c| c.is_finite()) {
            return Err(Error::NotFinite);
        }
        put_fixed(w, &self.name, NAME)?;
        put_fixed(w, &self.group, GROUP)?;
        w.put(&self.rgba)?;
        w.f32s(&coords)?;
        put_fixed(w, &self.owner, OWNER)
    }

    fn decode(r: &mut Reader<'_>) -> Result<Self, Error> {
        let name = fixed(r.take(NAME)?)?;
        let group = fixed(r.take(GROUP)?)?;
        let rgba = r.array()?;
        let position = r.finite3()?;
        let diameter = r.f32()?;
        if !diameter.is_finite() {
            return Err(Error::NotFinite);
        }
        let owner = fixed(r.take(OWNER)?)?;
        Ok(PointElement {
            name,
            group,
            rgba,
            position,
            diameter,
            owner,
        })
    }
}

/// The points of one POINT message.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PointList {
    /// The points, in message order.
    pub points: Vec<PointElement, MAX_POINTS>,
}

impl PointList {
    /// Writes 136 bytes per point; `NotFinite` for a NaN or infinite coordinate or diameter.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, Error> {
        let mut w = Writer::new(out);
        for p in &self.points {
            p.encode(&mut w)?;
        }
        Ok(w.len())
    }

    /// Reads a body that is a whole number of points (`BadBodySize` otherwise, `TooLarge` past
    /// [`MAX_POINTS`]).
    pub fn decode(content: &[u8]) -> Result<Self, Error> {
        if content.len() % POINT_ELEMENT_SIZE != 0 {
            return Err(Error::BadBodySize);
        }
        if content.len() / POINT_ELEMENT_SIZE > MAX_POINTS {
            return Err(Error::TooLarge);
        }
        let mut r = Reader::new(content);
        let mut points = Vec::new();
        while r.remaining() > 0 {
            points
                .push(PointElement::decode(&mut r)?)
                .map_err(|_| Error::TooLarge)?;
        }
        Ok(PointList { points })
    }
}
