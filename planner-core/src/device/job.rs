//! The job: the request in progress or last finished, planned one form per poll, and the
//! finished result served in chunks.

use super::upload::Upload;
use super::Core;
use crate::model::form::Form;
use crate::session::PlanSession;
use crate::wire::{Fault, PlanRequest, PlanResult, ReplyBody};

/// The request in progress or last finished.
// The session is large, but the service lives in a static with no heap to box it in.
#[allow(clippy::large_enum_variant)]
pub(super) enum Job {
    Idle,
    Uploading {
        id: u16,
        total: u16,
        crc: u32,
        received: u16,
    },
    Planning {
        id: u16,
        total_bytes: u16,
        request_crc: u32,
        session: PlanSession,
        done: u8,
        forms: u8,
        last: Option<(Form, bool)>,
    },
    Finished {
        id: u16,
        total_bytes: u16,
        request_crc: u32,
        len: u16,
        crc: u32,
    },
}

impl Core {
    /// Starts planning the uploaded request `id` (or stores the scenario's error as its result).
    pub(super) fn start_plan(&mut self, id: u16, up: Upload, tx: &mut dyn FnMut(&[u8])) {
        let total = up.total;
        let request =
            match postcard::take_from_bytes::<PlanRequest>(&self.upload[..usize::from(total)]) {
                Ok((r, [])) => r,
                _ => {
                    self.job = Job::Idle;
                    self.stats.undecodable += 1;
                    return self.fault(id, Fault::BadScenario, tx);
                }
            };
        match request.into_scenario().and_then(PlanSession::new) {
            Ok(session) => {
                let forms = session.form_count() as u8;
                self.job = Job::Planning {
                    id,
                    total_bytes: total,
                    request_crc: up.crc,
                    session,
                    done: 0,
                    forms,
                    last: None,
                };
                self.status(id, tx);
            }
            Err(e) => self.store_result(id, up, &Err(e), tx),
        }
    }

    /// Plans one form of the active plan; false if there is none. Never inlined, like
    /// `handle_frame`: the solver's frames and a frame's decoded request then never share the
    /// stack.
    #[inline(never)]
    pub(super) fn step(&mut self, tx: &mut dyn FnMut(&[u8])) -> bool {
        let Job::Planning {
            id,
            total_bytes,
            request_crc,
            session,
            done,
            last,
            ..
        } = &mut self.job
        else {
            return false;
        };
        let id = *id;
        let up = Upload {
            offset: 0,
            total: *total_bytes,
            crc: *request_crc,
        };
        match session.step() {
            Some(o) => {
                *last = Some((o.form, o.feasible));
                *done = done.saturating_add(1);
                self.status(id, tx);
            }
            None => self.finish(id, up, tx),
        }
        true
    }

    /// Picks the best form, builds its schedule and stores the encoded result. Never inlined, so
    /// its locals (the session moved out of the job, the result) are not on the stack while
    /// [`Core::step`] plans a form.
    #[inline(never)]
    fn finish(&mut self, id: u16, up: Upload, tx: &mut dyn FnMut(&[u8])) {
        if let Job::Planning { session, .. } = core::mem::replace(&mut self.job, Job::Idle) {
            // Called once `step` found no form left.
            let result: PlanResult = Ok(session.scheduled_so_far());
            self.stats.plans += 1;
            self.store_result(id, up, &result, tx);
        }
    }

    fn store_result(
        &mut self,
        id: u16,
        up: Upload,
        result: &PlanResult,
        tx: &mut dyn FnMut(&[u8]),
    ) {
        match postcard::to_slice(result, &mut self.result) {
            Ok(bytes) => {
                let len = bytes.len() as u16;
                let crc = crate::wire::crc::crc32(bytes);
                self.job = Job::Finished {
                    id,
                    total_bytes: up.total,
                    request_crc: up.crc,
                    len,
                    crc,
                };
                self.send(id, ReplyBody::Finished { len, crc }, tx);
            }
            // Cannot happen: the buffer is sized from `PlanResult::MAX_SIZE`, checked by tests.
            Err(_) => {
                self.job = Job::Idle;
                self.fault(id, Fault::Undecodable, tx);
            }
        }
    }

    pub(super) fn status(&mut self, id: u16, tx: &mut dyn FnMut(&[u8])) {
        let body = match &self.job {
            Job::Uploading {
                id: a,
                total,
                received,
                ..
            } if *a == id => ReplyBody::Uploaded {
                received: *received,
                total: *total,
            },
            Job::Planning {
                id: a,
                done,
                forms,
                last,
                ..
            } if *a == id => ReplyBody::Progress {
                done: *done,
                total: *forms,
                form: last.map(|(f, _)| f),
                feasible: last.is_some_and(|(_, ok)| ok),
            },
            Job::Finished {
                id: a, len, crc, ..
            } if *a == id => ReplyBody::Finished {
                len: *len,
                crc: *crc,
            },
            _ => ReplyBody::Fault(Fault::UnknownRequest),
        };
        self.send(id, body, tx);
    }

    pub(super) fn fetch(&mut self, id: u16, offset: u16, max_len: u16, tx: &mut dyn FnMut(&[u8])) {
        let len = match self.job {
            Job::Finished { id: a, len, .. } if a == id => len,
            _ => return self.status(id, tx),
        };
        let whole = self.result.get(..usize::from(len)).unwrap_or(&[]);
        let part = super::part_of(whole, offset, max_len);
        self.send(id, part, tx);
    }
}
