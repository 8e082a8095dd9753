//! A command's output files, written as a set: all or none.
//!
//! [`OutputSet::add`] writes each file to a temporary file in its target directory (so the final
//! rename never crosses a file system) and fsyncs it; [`OutputSet::commit`] renames them all into
//! place at the end, once every file of the command has been produced. Until then nothing the
//! user can see has changed: when the DXF fails after the SVG was written, or the PNG after the
//! JSON, the command's error leaves the old outputs (or none) and no new one.
//!
//! Temporary files are removed on every exit path: by `Drop` when the command returns early (an
//! error, a closed stdout), and by the process-wide signal handler the binary installs
//! (`cmd::device::install_handler`) on SIGINT, SIGTERM and SIGHUP through a registry of the
//! temporaries alive in this process ([`remove_staged`]). Writing files installs nothing.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

use anyhow::Context as _;

/// Temporary files alive in this process. The lock is held while a temporary is created and
/// written, so the signal handler never removes a file that is still being created.
static STAGED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
/// Distinguishes the temporaries of one process.
static NEXT: AtomicU64 = AtomicU64::new(0);

fn staged() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    STAGED.lock().unwrap_or_else(|p| p.into_inner())
}

/// Removes every temporary output of this process (for the signal handler, before it exits).
pub fn remove_staged() {
    for p in staged().drain(..) {
        let _ = std::fs::remove_file(p);
    }
}

/// One staged file: where it is written and where it goes.
#[derive(Debug)]
struct Staged {
    tmp: PathBuf,
    dest: PathBuf,
}

/// The output files of one command; see the module doc.
#[derive(Debug, Default)]
pub struct OutputSet {
    files: Vec<Staged>,
}

impl OutputSet {
    /// An empty set. A signal removes its temporaries where the binary installed its handler;
    /// they are removed on every other exit path in any case.
    pub fn new() -> OutputSet {
        OutputSet::default()
    }

    /// Writes `bytes` for `dest` to a temporary file beside it (creating the directory).
    /// Refuses a second file for the same destination: two outputs of one command would
    /// overwrite each other.
    pub fn add(&mut self, dest: &Path, bytes: &[u8]) -> anyhow::Result<()> {
        if self.files.iter().any(|s| s.dest == dest) {
            anyhow::bail!(
                "two outputs of this command would be written to {}",
                dest.display()
            );
        }
        let dir = match dest.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create {}", dir.display()))?;
        let name = dest
            .file_name()
            .with_context(|| format!("{} names no file", dest.display()))?
            .to_string_lossy();
        let tmp = dir.join(format!(
            ".{name}.flatcut-{}-{}.tmp",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        let mut reg = staged();
        reg.push(tmp.clone());
        let written = (|| {
            let mut f = std::fs::File::create(&tmp)?;
            f.write_all(bytes)?;
            f.sync_all()
        })();
        if let Err(e) = written {
            let _ = std::fs::remove_file(&tmp);
            reg.retain(|p| *p != tmp);
            return Err(e).with_context(|| format!("cannot write {}", dest.display()));
        }
        drop(reg);
        self.files.push(Staged {
            tmp,
            dest: dest.to_path_buf(),
        });
        Ok(())
    }

    /// The destinations staged so far, in the order they were added.
    pub fn destinations(&self) -> Vec<&Path> {
        self.files.iter().map(|s| s.dest.as_path()).collect()
    }

    /// Renames every staged file into place, in the order added. A rename within one directory
    /// fails only when the file system does (then the files not yet renamed are removed and the
    /// error names the first that failed; those already renamed stay).
    pub fn commit(mut self) -> anyhow::Result<Vec<PathBuf>> {
        let files = std::mem::take(&mut self.files);
        let mut done = Vec::with_capacity(files.len());
        let mut failed = None;
        for s in files {
            if failed.is_some() {
                let _ = std::fs::remove_file(&s.tmp);
            } else if let Err(e) = std::fs::rename(&s.tmp, &s.dest) {
                let _ = std::fs::remove_file(&s.tmp);
                failed = Some(
                    anyhow::Error::from(e).context(format!("cannot write {}", s.dest.display())),
                );
            } else {
                done.push(s.dest);
            }
            staged().retain(|p| *p != s.tmp);
        }
        match failed {
            Some(e) => Err(e),
            None => Ok(done),
        }
    }
}

impl Drop for OutputSet {
    /// A set dropped without `commit` (an error, an early return) leaves nothing behind.
    fn drop(&mut self) {
        let mut reg = staged();
        for s in self.files.drain(..) {
            let _ = std::fs::remove_file(&s.tmp);
            reg.retain(|p| *p != s.tmp);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn nothing_appears_before_commit_and_everything_after() {
        let d = tempfile::tempdir().unwrap();
        let mut set = OutputSet::new();
        set.add(&d.path().join("a.svg"), b"svg").unwrap();
        set.add(&d.path().join("sub/b.dxf"), b"dxf").unwrap();
        assert!(!d.path().join("a.svg").exists() && !d.path().join("sub/b.dxf").exists());
        let done = set.commit().unwrap();
        assert_eq!(done.len(), 2);
        assert_eq!(std::fs::read(d.path().join("a.svg")).unwrap(), b"svg");
        assert_eq!(names(d.path()), ["a.svg", "sub"]);
        assert_eq!(names(&d.path().join("sub")), ["b.dxf"]);
    }

    #[test]
    fn a_set_dropped_before_commit_leaves_the_old_files_and_no_temporary() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("a.svg"), b"old").unwrap();
        {
            let mut set = OutputSet::new();
            set.add(&d.path().join("a.svg"), b"new").unwrap();
            // the second output fails: its directory is a file
            std::fs::write(d.path().join("blocked"), b"").unwrap();
            assert!(set.add(&d.path().join("blocked/b.dxf"), b"x").is_err());
        }
        assert_eq!(std::fs::read(d.path().join("a.svg")).unwrap(), b"old");
        assert_eq!(names(d.path()), ["a.svg", "blocked"]);
    }

    #[test]
    fn two_outputs_to_one_file_are_refused() {
        let d = tempfile::tempdir().unwrap();
        let mut set = OutputSet::new();
        set.add(&d.path().join("flat-a_b.obj"), b"1").unwrap();
        let e = set.add(&d.path().join("flat-a_b.obj"), b"2").unwrap_err();
        assert!(e.to_string().contains("two outputs"), "{e}");
    }

    #[test]
    fn live_temporaries_are_registered_for_the_signal_handler() {
        let d = tempfile::tempdir().unwrap();
        let mut set = OutputSet::new();
        set.add(&d.path().join("big.obj"), b"v 0 0 0").unwrap();
        let tmp = d.path().join(&names(d.path())[0]);
        assert!(staged().contains(&tmp));
        drop(set);
        assert!(!staged().contains(&tmp) && !tmp.exists());
    }
}
