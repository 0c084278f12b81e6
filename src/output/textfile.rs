//! `--prometheus-textfile FILE.prom`: a file that is never seen
//! half-written. node_exporter's textfile collector may read it at any
//! moment, while a timer's run rewrites it: the text goes to a temporary
//! file beside it (same directory, so same file system; a name not ending
//! in `.prom`, which the collector skips), is synced, then renamed over the
//! old one, which POSIX makes atomic.

use std::fs::File;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// The temporary file, created when the run starts (so an unwritable
/// directory fails before anything is sent) and renamed at its end.
pub(crate) struct Textfile {
    path: PathBuf,
    temp: PathBuf,
    file: Option<File>,
}

impl Textfile {
    pub(crate) fn create(path: &Path) -> io::Result<Self> {
        let parent = path.parent().filter(|d| !d.as_os_str().is_empty());
        let dir = parent.unwrap_or(Path::new("."));
        let name = path
            .file_name()
            .map_or_else(|| "metrics".into(), |n| n.to_string_lossy().into_owned());
        let temp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
        let file = File::create(&temp)?;
        Ok(Textfile {
            path: path.to_path_buf(),
            temp,
            file: Some(file),
        })
    }

    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// Writes `text` and puts it in place at once.
    pub(crate) fn commit(mut self, text: &str) -> io::Result<()> {
        let mut file = self.file.take().expect("committed once");
        file.write_all(text.as_bytes())?;
        file.sync_all()?;
        drop(file);
        std::fs::rename(&self.temp, &self.path)
    }
}

impl Drop for Textfile {
    /// A run that ends before its commit leaves no temporary file behind.
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.temp);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_file_appears_whole_and_no_temporary_is_left() {
        let dir = std::env::temp_dir().join(format!("mavping-textfile-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("mavping.prom");
        std::fs::write(&path, "old\n").unwrap();
        let t = Textfile::create(&path).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old\n");
        t.commit("new 1\n").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new 1\n");
        drop(Textfile::create(&path).unwrap());
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(left.len(), 1, "{left:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
