//! Largest postcard encoding of each wire type, so every buffer is sized from the types.
//!
//! postcard's own `MaxSize` derive cannot see heapless 0.9 types, so the bound is stated here per
//! type. Each bound is checked by a test that encodes a worst-case value of that type and asserts
//! the encoding has exactly that length; the tests build their values with struct literals, so a
//! field added to a type breaks them until its bound is updated too.

use crate::error::{Field, PlanError};
use crate::execute::plan_with_schedule::ScheduledPlan;
use crate::execute::schedule::{Op, Posture, Schedule, ScheduleError, Step, Steps};
use crate::model::form::{Form, FormSet, SegmentKind};
use crate::model::scenario::{Driver, Entry, Needle, Obstacle, PlannerOptions, Target, Weights};
use crate::report::{FormOutcome, Insertion, PlanReport, SegmentPlan, SolveStatus};

/// A type whose postcard encoding never exceeds `MAX_SIZE` bytes.
pub trait MaxSize {
    /// Largest encoding in bytes.
    const MAX_SIZE: usize;
}

/// Bytes of a postcard varint holding at most `max`.
pub const fn varint_len(max: u64) -> usize {
    let mut n = 1;
    let mut v = max >> 7;
    while v != 0 {
        n += 1;
        v >>= 7;
    }
    n
}

/// The larger of two sizes (for enums: the largest variant).
pub const fn max(a: usize, b: usize) -> usize {
    if a > b {
        a
    } else {
        b
    }
}

macro_rules! fixed {
    ($($t:ty => $n:expr),* $(,)?) => { $(impl MaxSize for $t { const MAX_SIZE: usize = $n; })* };
}

fixed! {
    u8 => 1,
    bool => 1,
    u16 => varint_len(u16::MAX as u64),
    u32 => varint_len(u32::MAX as u64),
    f32 => 4,
    // Unit-only enums below 128 variants: one varint byte.
    SegmentKind => 1,
    SolveStatus => 1,
    crate::model::scenario::Workspace => 1,
    crate::model::scenario::RiskMeasure => 1,
    Form => 2,
    FormSet => u32::MAX_SIZE,
}

impl<T: MaxSize, const N: usize> MaxSize for [T; N] {
    const MAX_SIZE: usize = N * T::MAX_SIZE;
}

impl<T: MaxSize, const N: usize> MaxSize for heapless::Vec<T, N> {
    const MAX_SIZE: usize = varint_len(N as u64) + N * T::MAX_SIZE;
}

impl<const N: usize> MaxSize for heapless::String<N> {
    const MAX_SIZE: usize = varint_len(N as u64) + N;
}

impl<T: MaxSize> MaxSize for Option<T> {
    const MAX_SIZE: usize = 1 + T::MAX_SIZE;
}

impl<T: MaxSize, E: MaxSize> MaxSize for Result<T, E> {
    const MAX_SIZE: usize = 1 + max(T::MAX_SIZE, E::MAX_SIZE);
}

impl MaxSize for Needle {
    const MAX_SIZE: usize = 4 * f32::MAX_SIZE;
}
impl MaxSize for Entry {
    const MAX_SIZE: usize = 2 * <[f32; 3]>::MAX_SIZE + f32::MAX_SIZE;
}
impl MaxSize for Target {
    const MAX_SIZE: usize = <[f32; 3]>::MAX_SIZE + f32::MAX_SIZE;
}
impl MaxSize for Obstacle {
    const MAX_SIZE: usize = <[f32; 3]>::MAX_SIZE + f32::MAX_SIZE;
}
impl MaxSize for Weights {
    const MAX_SIZE: usize = 4 * f32::MAX_SIZE;
}
impl MaxSize for Driver {
    const MAX_SIZE: usize = 4 * f32::MAX_SIZE;
}
impl MaxSize for PlannerOptions {
    const MAX_SIZE: usize =
        u8::MAX_SIZE + FormSet::MAX_SIZE + 1 + 1 + 2 * f32::MAX_SIZE + Option::<f32>::MAX_SIZE;
}
impl MaxSize for Field {
    // Variant tag, then at most one u16 (an obstacle index).
    const MAX_SIZE: usize = 1 + u16::MAX_SIZE;
}
impl MaxSize for PlanError {
    // The widest variant is `TooManyObstacles { given: u16, capacity: u16 }`.
    const MAX_SIZE: usize = 1 + max(Field::MAX_SIZE, 2 * u16::MAX_SIZE);
}
impl MaxSize for Insertion {
    const MAX_SIZE: usize = 3 * f32::MAX_SIZE + <[f32; 3]>::MAX_SIZE;
}
impl MaxSize for SegmentPlan {
    const MAX_SIZE: usize = SegmentKind::MAX_SIZE + 2 * f32::MAX_SIZE;
}
impl MaxSize for FormOutcome {
    const MAX_SIZE: usize = Form::MAX_SIZE
        + SolveStatus::MAX_SIZE
        + bool::MAX_SIZE
        + 7 * f32::MAX_SIZE
        + Insertion::MAX_SIZE
        + crate::report::Segments::MAX_SIZE
        + 2 * u32::MAX_SIZE;
}
impl MaxSize for PlanReport {
    const MAX_SIZE: usize = crate::report::FormOutcomes::MAX_SIZE + <Option<u8>>::MAX_SIZE;
}
impl MaxSize for Op {
    // Variant tag, then the widest variant: `InsertSpin { length_mm: f32, turns: u32 }`.
    const MAX_SIZE: usize = 1 + f32::MAX_SIZE + u32::MAX_SIZE;
}
impl MaxSize for Step {
    const MAX_SIZE: usize = Op::MAX_SIZE + f32::MAX_SIZE;
}
impl MaxSize for Posture {
    const MAX_SIZE: usize = 2 * <[f32; 3]>::MAX_SIZE + 3 * f32::MAX_SIZE;
}
impl MaxSize for Schedule {
    const MAX_SIZE: usize = Posture::MAX_SIZE + Steps::MAX_SIZE + 2 * f32::MAX_SIZE;
}
impl MaxSize for ScheduleError {
    // Variant tag, then at most a `PlanError` (`Driver`).
    const MAX_SIZE: usize = 1 + PlanError::MAX_SIZE;
}
impl MaxSize for ScheduledPlan {
    const MAX_SIZE: usize =
        PlanReport::MAX_SIZE + <Option<Result<Schedule, ScheduleError>> as MaxSize>::MAX_SIZE;
}

impl MaxSize for crate::execute::perturbation::Perturbation {
    const MAX_SIZE: usize = 11 * f32::MAX_SIZE;
}
impl MaxSize for crate::execute::risk::Execution {
    // Variant tag, then the widest: `Steered(NoiseModel)`.
    const MAX_SIZE: usize = 1 + crate::steer::NoiseModel::MAX_SIZE;
}
impl MaxSize for crate::chance::ChanceFigures {
    const MAX_SIZE: usize = 2 * Option::<f32>::MAX_SIZE
        + heapless::Vec::<f32, { crate::MAX_OBSTACLES }>::MAX_SIZE
        + u32::MAX_SIZE
        + bool::MAX_SIZE;
}
