//! Where a scenario's entry and target are: given in the file, or read from 3D Slicer markups.

use super::file::ScenarioFile;
use crate::anatomy::markups::read_point;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

impl ScenarioFile {
    /// The entry point (RAS mm): `entry.position`, or the point of `entry.markups`.
    pub fn entry_position(&self) -> Result<[f32; 3]> {
        let e = &self.entry;
        self.point(
            "entry",
            e.position,
            e.markups.as_deref(),
            e.point.as_deref(),
        )
    }

    /// The target (RAS mm): `target.position`, or the point of `target.markups`.
    pub fn target_position(&self) -> Result<[f32; 3]> {
        let t = &self.target;
        self.point(
            "target",
            t.position,
            t.markups.as_deref(),
            t.point.as_deref(),
        )
    }

    fn point(
        &self,
        table: &str,
        position: Option<[f32; 3]>,
        markups: Option<&Path>,
        label: Option<&str>,
    ) -> Result<[f32; 3]> {
        match (position, markups) {
            (Some(p), None) => {
                if label.is_some() {
                    bail!("{table}.point names a markups point: give {table}.markups too");
                }
                Ok(p)
            }
            (None, Some(file)) => {
                let path = self.relative(file);
                read_point(&path, label).with_context(|| format!("in {table}.markups"))
            }
            (Some(_), Some(_)) => bail!("give {table}.position or {table}.markups, not both"),
            (None, None) => bail!("{table}.position (or {table}.markups) is required"),
        }
    }

    /// `file` relative to the scenario's folder (as it is, when absolute or without a folder).
    pub fn relative(&self, file: &Path) -> PathBuf {
        match &self.base_dir {
            Some(dir) if file.is_relative() => dir.join(file),
            _ => file.to_path_buf(),
        }
    }
}
