//! The insertion log: one JSON object a line (the plan, each reading, each command, the stop),
//! flushed line by line so that it is complete whenever the insertion stops, however it stops.

use anyhow::{Context, Result};
use serde::Serialize;
use serde_json::{json, Value};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::time::Instant;

/// Where the log goes (nowhere without `--log`).
pub struct InsertionLog {
    file: Option<BufWriter<File>>,
    start: Instant,
    /// The first write that failed (the insertion goes on: the robot must be commanded).
    pub failure: Option<String>,
}

impl InsertionLog {
    /// A log written to `path` (created or truncated), or none.
    pub fn create(path: Option<&Path>) -> Result<InsertionLog> {
        let file = path
            .map(|p| {
                File::create(p).with_context(|| format!("cannot write the log {}", p.display()))
            })
            .transpose()?;
        Ok(InsertionLog {
            file: file.map(BufWriter::new),
            start: Instant::now(),
            failure: None,
        })
    }

    /// Writes one event: `{"event": EVENT, "t_ms": ms since the log began, ...fields}`.
    pub fn write(&mut self, event: &str, fields: impl Serialize) {
        let Some(f) = self.file.as_mut() else {
            return;
        };
        let mut line = match serde_json::to_value(fields) {
            Ok(Value::Object(m)) => Value::Object(m),
            Ok(other) => json!({ "value": other }),
            Err(e) => json!({ "unserialisable": e.to_string() }),
        };
        if let Value::Object(m) = &mut line {
            m.insert("event".into(), Value::from(event));
            let t_ms = self.start.elapsed().as_secs_f64() * 1e3;
            m.insert("t_ms".into(), Value::from(t_ms));
        }
        let written = serde_json::to_writer(&mut *f, &line)
            .map_err(std::io::Error::from)
            .and_then(|()| f.write_all(b"\n"))
            .and_then(|()| f.flush());
        if let Err(e) = written {
            self.failure.get_or_insert(e.to_string());
        }
    }

    /// The registration `name` the tracker streamed, taken for the session.
    pub fn registration(&mut self, name: &str, reg: &needle_igtl::Transform) {
        let (rotation, translation_mm) = (reg.rotation(), reg.translation());
        self.write(
            "registration",
            json!({ "name": name, "rotation": rotation, "translation_mm": translation_mm }),
        );
    }

    /// No registration `name` came within `waited`.
    pub fn no_registration(&mut self, name: &str, waited: std::time::Duration) {
        let waited_ms = waited.as_millis() as u64;
        self.write(
            "no_registration",
            json!({ "name": name, "waited_ms": waited_ms }),
        );
    }
}
