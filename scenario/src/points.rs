//! Where a scenario's entry and target are: given in the file, or read from 3D Slicer markups.

use super::file::ScenarioFile;
use anyhow::{bail, Context, Result};
use needle_anatomy::interior::deepest_point;
use needle_anatomy::label_map::LabelMap;
use needle_anatomy::markups::read_point;
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

    /// The target (RAS mm): `target.position`, the point of `target.markups`, or the deepest
    /// point of segment `target.label`.
    pub fn target_position(&self) -> Result<[f32; 3]> {
        let t = &self.target;
        if let Some(label) = t.label {
            if t.position.is_some() || t.markups.is_some() {
                bail!("give one of target.position, target.markups and target.label");
            }
            return self.deepest_of(label).context("in target.label");
        }
        if t.label_file.is_some() {
            bail!("target.label_file names the map of target.label: give target.label too");
        }
        self.point(
            "target",
            t.position,
            t.markups.as_deref(),
            t.point.as_deref(),
        )
    }

    /// The deepest point of segment `label`, in `target.label_file` or the first `[[anatomy]]`
    /// map that holds it.
    fn deepest_of(&self, label: i64) -> Result<[f32; 3]> {
        let files: Vec<PathBuf> = match &self.target.label_file {
            Some(f) => vec![self.relative(f)],
            None => self
                .anatomy
                .iter()
                .map(|a| self.relative(&a.file))
                .collect(),
        };
        if files.is_empty() {
            bail!("label {label}: no label map (give target.label_file or an [[anatomy]] entry)");
        }
        for path in &files {
            let map = LabelMap::read(path)?;
            if map.labels.contains(&label) {
                let (p, _) = deepest_point(&map, label)?;
                return Ok(p.map(|v| v as f32));
            }
        }
        let names: Vec<String> = files.iter().map(|p| p.display().to_string()).collect();
        bail!("label {label} is in none of {}", names.join(", "))
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
