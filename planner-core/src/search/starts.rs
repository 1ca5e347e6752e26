//! What a form's search starts from besides its own sweep: the best paths of the forms one
//! segment shorter, and which of them were planned already.

use crate::model::form::{Form, SegmentKind, MAX_CONTROL_DEGREE};
use crate::model::scenario::Scenario;
use crate::optim::problem::{Problem, Vars};
use crate::report::FormOutcome;

/// Starts for `form` made from the best paths of the forms one segment shorter: the missing
/// segment is inserted with zero length, so a form never reports a worse path than a sub-form
/// it contains. Each start comes with its plane-mode side assignment.
#[inline(never)]
pub(crate) fn extension_starts(
    scenario: &Scenario,
    form: Form,
    previous: &[FormOutcome],
) -> heapless::Vec<(u8, Vars), EXTENSIONS> {
    let mut out = heapless::Vec::new();
    for o in previous
        .iter()
        .filter(|o| o.feasible && o.form.len() + 1 == form.len())
    {
        for gap in 0..form.len() {
            let shorter = (0..form.len()).filter(|&i| i != gap).map(|i| form.kind(i));
            if !shorter.eq((0..o.form.len()).map(|i| o.form.kind(i))) {
                continue;
            }
            let mut lengths = [0.0; MAX_CONTROL_DEGREE];
            let mut bevels = [0.0; MAX_CONTROL_DEGREE];
            for (k, i) in (0..form.len()).filter(|&i| i != gap).enumerate() {
                lengths[i] = o.segments[k].length;
                bevels[i] = o.segments[k].bevel_deg.to_radians();
            }
            let mut sides = 0u8;
            let mut facing_negative = false;
            let mut arc = 0;
            for i in 0..form.len() {
                if form.kind(i) == SegmentKind::Arc {
                    if libm::fabsf(bevels[i]) > 1.0 {
                        facing_negative = !facing_negative;
                    }
                    if facing_negative {
                        sides |= 1 << arc;
                    }
                    arc += 1;
                }
            }
            let p = Problem::new(scenario, form, sides);
            let mut x = [0.0; crate::optim::problem::MAX_VARS];
            p.set_angles(
                &mut x,
                o.insertion.theta1_deg.to_radians(),
                o.insertion.theta2_deg.to_radians(),
            );
            for i in 0..form.len() {
                x[p.length_var(i)] = lengths[i] / p.radius;
                if let Some(k) = p.bevel_var(i) {
                    x[k] = bevels[i];
                }
            }
            if out.push((sides, x)).is_err() {
                return out;
            }
        }
    }
    out
}

/// Extension starts kept per form (forms one shorter times insertion places).
pub(crate) const EXTENSIONS: usize = 16;

/// Bit i set: the form without its line i is among the `previous` outcomes (planned already,
/// feasible or not).
pub(crate) fn planned_without(form: Form, previous: &[FormOutcome]) -> u8 {
    let mut out = 0u8;
    for i in (0..form.len()).filter(|&i| form.kind(i) == SegmentKind::Line) {
        let shorter = || {
            (0..form.len())
                .filter(move |&k| k != i)
                .map(|k| form.kind(k))
        };
        let planned = previous.iter().any(|o| {
            o.form.len() + 1 == form.len()
                && shorter().eq((0..o.form.len()).map(|k| o.form.kind(k)))
        });
        if planned {
            out |= 1 << i;
        }
    }
    out
}
