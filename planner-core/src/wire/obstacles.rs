//! The obstacle list as it travels: any count the upload buffer can carry decodes, the device keeps
//! what it has room for and counts the rest, so "too many obstacles" is a typed planner error
//! ([`PlanError::TooManyObstacles`]) instead of an undecodable request.

use crate::error::PlanError;
use crate::model::scenario::{Obstacle, Obstacles, DEVICE_MAX_OBSTACLES};
use core::fmt;
use serde::de::{SeqAccess, Visitor};
use serde::ser::SerializeSeq;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// Obstacles the wire format can carry in one plan request: twice what the device holds (and so
/// every scenario the host holds), so a scenario over the device's capacity still arrives and is
/// answered with a count. The same on every build: the format must not depend on who decodes it.
pub const WIRE_MAX_OBSTACLES: usize = 2 * DEVICE_MAX_OBSTACLES;

/// Obstacles as sent: the ones that fit, and how many were sent in all.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct WireObstacles {
    kept: Obstacles,
    given: u16,
}

impl WireObstacles {
    /// The list of a scenario (always within capacity).
    pub fn from_obstacles(obstacles: &Obstacles) -> Self {
        WireObstacles {
            kept: obstacles.clone(),
            given: obstacles.len() as u16,
        }
    }

    /// Number of obstacles the sender listed.
    pub fn given(&self) -> u16 {
        self.given
    }

    /// The obstacles, or the typed error for a list over the device's capacity (also where a
    /// host decodes the request, as hil-sim does: it must refuse what the board refuses).
    pub fn into_obstacles(self) -> Result<Obstacles, PlanError> {
        if usize::from(self.given) > DEVICE_MAX_OBSTACLES {
            Err(PlanError::TooManyObstacles {
                given: self.given,
                capacity: DEVICE_MAX_OBSTACLES as u16,
            })
        } else {
            Ok(self.kept)
        }
    }
}

impl Serialize for WireObstacles {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut seq = s.serialize_seq(Some(self.kept.len()))?;
        for o in &self.kept {
            seq.serialize_element(o)?;
        }
        seq.end()
    }
}

struct CountingVisitor;

impl<'de> Visitor<'de> for CountingVisitor {
    type Value = WireObstacles;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a sequence of obstacles")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<WireObstacles, A::Error> {
        let mut out = WireObstacles::default();
        while let Some(o) = seq.next_element::<Obstacle>()? {
            // Past capacity the element is still decoded (the frame must be well-formed), then counted.
            let _ = out.kept.push(o);
            out.given = out.given.saturating_add(1);
        }
        Ok(out)
    }
}

impl<'de> Deserialize<'de> for WireObstacles {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_seq(CountingVisitor)
    }
}
