//! The workbench's design state: the document being edited, the design it loads to (always one
//! the design loader accepts: an edit it refuses is refused whole), undo and redo, and saving
//! back to the file.

use std::path::Path;

use flatcut::design::Design;
use serde_json::Value as Json;

use crate::document::{DesignDocument, DocumentError};
use crate::opened::Opened;

/// Most edits kept for undo.
pub const UNDO_DEPTH: usize = 200;

/// Why an edit or a save was refused. The message is what the command line would say about the
/// same file.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// The design text (TOML or JSON) cannot be parsed or edited.
    #[error(transparent)]
    Document(#[from] DocumentError),
    /// The design loader refuses the edited design.
    #[error(transparent)]
    Design(#[from] flatcut::design::DesignError),
    /// The design file could not be written.
    #[error("{path}: {message}")]
    Save {
        /// The design file.
        path: String,
        /// The operating system's error.
        message: String,
    },
    /// Undo or redo with an empty history; the operation's name (`"undo"`, `"redo"`).
    #[error("nothing to {0}")]
    Nothing(&'static str),
}

/// The design being edited.
pub struct Bench {
    /// The input the workbench was started on.
    pub opened: Opened,
    doc: DesignDocument,
    design: Design,
    /// Bumped by every change of the design.
    revision: u64,
    /// The text last written to (or read from) the file.
    saved_text: Option<String>,
    undo: Vec<DesignDocument>,
    redo: Vec<DesignDocument>,
}

impl Bench {
    /// The workbench on an opened input.
    pub fn new(opened: Opened) -> Result<Bench, BenchError> {
        let path = opened.design_path.display().to_string();
        let is_json = opened
            .design_path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        let doc = DesignDocument::parse(&opened.text, is_json, &path)?;
        let design = load(&doc, &opened.design_path)?;
        let saved_text = opened.design_path.is_file().then(|| opened.text.clone());
        Ok(Bench {
            opened,
            doc,
            design,
            revision: 1,
            saved_text,
            undo: Vec::new(),
            redo: Vec::new(),
        })
    }

    /// The document being edited.
    pub fn document(&self) -> &DesignDocument {
        &self.doc
    }

    /// The design as loaded from the current document.
    pub fn design(&self) -> &Design {
        &self.design
    }

    /// The design's revision: 1 when opened, one more for each change (edit, undo, redo).
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Whether the file holds the design as it is now.
    pub fn saved(&self) -> bool {
        self.saved_text.as_deref() == Some(self.doc.text().as_str())
    }

    /// Whether there is an edit to undo (at most [`UNDO_DEPTH`] are kept).
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    /// Whether there is an undone edit to redo (a new edit clears them).
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// The design as its JSON tree.
    pub fn tree(&self) -> Json {
        self.doc.tree()
    }

    /// The document's text as it would be saved.
    pub fn text(&self) -> String {
        self.doc.text()
    }

    /// Replaces the design by `tree` (merged into the document, see [`crate::document`]) when
    /// the design loader accepts the result; returns the new revision.
    pub fn set_tree(&mut self, tree: &Json) -> Result<u64, BenchError> {
        let mut doc = self.doc.clone();
        doc.apply(tree)?;
        let design = load(&doc, &self.opened.design_path)?;
        if design == self.design && doc.text() == self.doc.text() {
            return Ok(self.revision);
        }
        let old = std::mem::replace(&mut self.doc, doc);
        self.undo.push(old);
        if self.undo.len() > UNDO_DEPTH {
            self.undo.remove(0);
        }
        self.redo.clear();
        self.design = design;
        self.revision += 1;
        Ok(self.revision)
    }

    /// Goes back one edit.
    pub fn undo(&mut self) -> Result<u64, BenchError> {
        let doc = self.undo.pop().ok_or(BenchError::Nothing("undo"))?;
        self.step(doc, true)
    }

    /// Goes forward one undone edit.
    pub fn redo(&mut self) -> Result<u64, BenchError> {
        let doc = self.redo.pop().ok_or(BenchError::Nothing("redo"))?;
        self.step(doc, false)
    }

    /// Makes `doc` current, keeping the present one on the other stack. An
    /// undone design gets a new revision number, so a result computed for it is never mistaken
    /// for the present design's.
    fn step(&mut self, doc: DesignDocument, undoing: bool) -> Result<u64, BenchError> {
        let design = load(&doc, &self.opened.design_path)?;
        let old = std::mem::replace(&mut self.doc, doc);
        if undoing {
            self.redo.push(old);
        } else {
            self.undo.push(old);
        }
        self.design = design;
        self.revision += 1;
        Ok(self.revision)
    }

    /// Writes the document to the design file (a temporary file beside it, renamed into place,
    /// so a failed save leaves the old file whole).
    pub fn save(&mut self) -> Result<&Path, BenchError> {
        let path = &self.opened.design_path;
        let text = self.doc.text();
        write_atomically(path, text.as_bytes()).map_err(|e| BenchError::Save {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        self.saved_text = Some(text);
        Ok(path)
    }
}

/// Loads the document as the command line would load the saved file.
fn load(doc: &DesignDocument, path: &Path) -> Result<Design, BenchError> {
    Ok(Design::from_file_text(&doc.text(), path)?)
}

/// Writes `bytes` to `path` through a temporary file in the same directory, synced and renamed.
fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write as _;
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
