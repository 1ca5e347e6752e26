//! Size bounds of the steering messages' types (see [`crate::steer`]): a reading, the device's
//! answer and the controller's settings all travel in one frame.

use super::max_size::{max, MaxSize};
use crate::execute::schedule::{Step, Steps};
use crate::steer::{
    Command, NoiseModel, Pose, Reading, SteerConfig, SteerReply, SteerStats, StopReason,
    TipMeasurement,
};

impl MaxSize for Pose {
    const MAX_SIZE: usize = 2 * <[f32; 3]>::MAX_SIZE + Option::<[f32; 3]>::MAX_SIZE;
}
impl MaxSize for TipMeasurement {
    const MAX_SIZE: usize =
        u32::MAX_SIZE + 2 * f32::MAX_SIZE + Option::<Pose>::MAX_SIZE + Option::<[f32; 3]>::MAX_SIZE;
}
impl MaxSize for StopReason {
    const MAX_SIZE: usize = 1;
}
impl MaxSize for Reading {
    const MAX_SIZE: usize = 1;
}
impl MaxSize for Command {
    // Variant tag, then the widest: `Replace(Steps)`.
    const MAX_SIZE: usize = 1 + max(Steps::MAX_SIZE, StopReason::MAX_SIZE);
}
impl MaxSize for SteerReply {
    const MAX_SIZE: usize = u32::MAX_SIZE
        + Command::MAX_SIZE
        + Reading::MAX_SIZE
        + bool::MAX_SIZE
        + 2 * f32::MAX_SIZE
        + u32::MAX_SIZE;
}
impl MaxSize for SteerStats {
    const MAX_SIZE: usize = 9 * u32::MAX_SIZE;
}
impl MaxSize for NoiseModel {
    const MAX_SIZE: usize = 14 * f32::MAX_SIZE;
}
impl MaxSize for SteerConfig {
    const MAX_SIZE: usize = NoiseModel::MAX_SIZE + 4 * f32::MAX_SIZE + u32::MAX_SIZE;
}

// A step's bound is what `Steps` counts with.
const _: () = assert!(Steps::MAX_SIZE > Step::MAX_SIZE);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::execute::schedule::Op;
    use crate::steer::StopReason;

    fn encoded_len<T: serde::Serialize>(v: &T) -> usize {
        let mut buf = [0u8; 512];
        postcard::to_slice(v, &mut buf).map(|b| b.len()).unwrap()
    }

    #[test]
    fn worst_case_encodings_have_exactly_the_stated_sizes() {
        let m = TipMeasurement {
            seq: u32::MAX,
            depth_mm: 1.0,
            base_deg: 2.0,
            pose: Some(Pose {
                position: [1.0; 3],
                heading: [0.0, 0.0, 1.0],
                bevel: Some([0.0, 1.0, 0.0]),
            }),
            target: Some([3.0; 3]),
        };
        assert_eq!(encoded_len(&m), TipMeasurement::MAX_SIZE);
        let step = Step {
            op: Op::InsertSpin {
                length_mm: 1.0,
                turns: u32::MAX,
            },
            duration_s: 1.0,
        };
        let mut steps = Steps::new();
        while steps.push(step).is_ok() {}
        let reply = SteerReply {
            seq: u32::MAX,
            command: Command::Replace(steps),
            reading: Reading::Fused,
            replanned: true,
            predicted_error_mm: 0.1,
            predicted_clearance_mm: 2.0,
            evaluations: u32::MAX,
        };
        assert_eq!(encoded_len(&reply), SteerReply::MAX_SIZE);
        let stop = Command::Stop(StopReason::BadMeasurement);
        assert!(encoded_len(&stop) <= Command::MAX_SIZE);
        let config = SteerConfig {
            iterations: u32::MAX,
            ..SteerConfig::DEFAULT
        };
        assert_eq!(encoded_len(&config), SteerConfig::MAX_SIZE);
        let stats = SteerStats {
            readings: u32::MAX,
            replans: u32::MAX,
            replan_failures: u32::MAX,
            no_fix: u32::MAX,
            outliers: u32::MAX,
            target_outliers: u32::MAX,
            target_jumps: u32::MAX,
            stale: u32::MAX,
            repeated: u32::MAX,
        };
        assert_eq!(encoded_len(&stats), SteerStats::MAX_SIZE);
    }
}
