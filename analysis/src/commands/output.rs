//! Where the analysis commands' output goes: progress bars on a terminal, files announced on
//! stderr (opened before the work where it is long), plot titles named after the scenario file.

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use std::fs::{File, OpenOptions};
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

/// A progress bar on a terminal, nothing otherwise.
pub fn progress(len: usize, what: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len as u64);
    if let Ok(style) =
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} {elapsed_precise} eta {eta}")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_string());
    bar
}

/// Writes `text` to `path` and says so on stderr.
pub fn write(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// The scenario file's name, for plot titles.
pub fn title_of(file: &Path) -> String {
    file.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// An output file opened before the work that fills it, so that a path that cannot be written
/// fails at once rather than after a long run. It is emptied only when written; a file it
/// created is removed again if the work fails before that.
pub struct OutputFile {
    path: PathBuf,
    file: File,
    created: bool,
}

impl OutputFile {
    /// Opens (or creates) `path` for writing, leaving what it holds until [`OutputFile::write`].
    pub fn open(path: &Path) -> Result<OutputFile> {
        let created = !path.exists();
        let file = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)
            .with_context(|| format!("cannot write {}", path.display()))?;
        Ok(OutputFile {
            path: path.to_path_buf(),
            file,
            created,
        })
    }

    /// Replaces the file's content with `text` and says so on stderr.
    pub fn write(mut self, text: &str) -> Result<()> {
        let context = || format!("cannot write {}", self.path.display());
        self.file.set_len(0).with_context(context)?;
        self.file.write_all(text.as_bytes()).with_context(context)?;
        self.created = false;
        eprintln!("wrote {}", self.path.display());
        Ok(())
    }
}

impl Drop for OutputFile {
    fn drop(&mut self) {
        if self.created {
            // Nothing was written: leave no empty file behind where there was none.
            let _ = std::fs::remove_file(&self.path);
        }
    }
}
