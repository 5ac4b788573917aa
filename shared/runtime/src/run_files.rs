//! The per-user private directory of run files (effective manifests,
//! `status.json`, snapshots handed to restarted processes, iceoryx2's own
//! files): `$XDG_RUNTIME_DIR/nauta` when that is a private directory of the
//! user, else `$TMPDIR/nauta-<uid>` (`/tmp` without `TMPDIR`).
//!
//! The directory is created with mode 0700 and then checked (not a symlink,
//! a directory, owned by the current user, mode exactly 0700); anything else is
//! refused, so another local user can neither read a run's files nor plant a
//! symlink for a launcher to follow. Every file in it is created exclusively
//! without following symlinks (`O_CREAT|O_EXCL|O_NOFOLLOW`, mode 0600); a file
//! that is rewritten is written to a new temporary file and renamed over; a
//! file is read only if it is a regular file the current user owns.

use std::io::{Read as _, Write as _};
use std::os::unix::fs::{DirBuilderExt as _, MetadataExt as _, OpenOptionsExt as _};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

/// Mode of every run directory.
pub const DIR_MODE: u32 = 0o700;
/// Mode of every run file.
pub const FILE_MODE: u32 = 0o600;

/// A run directory or file that cannot be used safely.
#[derive(Debug, thiserror::Error)]
pub enum RunFileError {
    /// The directory could not be created or inspected.
    #[error("cannot create the run directory {path}: {source}")]
    Create {
        /// The directory.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The directory exists but is not private to this user.
    #[error(
        "refusing the run directory {path}: {why}; it must be a directory (not a symlink) owned by uid {uid} with mode 0700 (remove it, or set TMPDIR elsewhere)"
    )]
    NotPrivate {
        /// The directory.
        path: PathBuf,
        /// What is wrong with it.
        why: String,
        /// The current user.
        uid: u32,
    },
    /// A file in a run directory is not a regular file of this user.
    #[error("refusing {path}: {why} (run files must be regular files owned by uid {uid})")]
    Untrusted {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        why: String,
        /// The current user.
        uid: u32,
    },
    /// Reading or writing a run file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// The effective user id of this process.
pub fn uid() -> u32 {
    // SAFETY: geteuid(2) has no preconditions and cannot fail.
    unsafe { libc::geteuid() }
}

/// Where the run directory is (not created): `$XDG_RUNTIME_DIR/nauta` if
/// `XDG_RUNTIME_DIR` is set and is a directory owned by this user that no
/// one else may enter, else `$TMPDIR/nauta-<uid>`.
pub fn runs_dir_path() -> PathBuf {
    if let Some(xdg) = std::env::var_os("XDG_RUNTIME_DIR").filter(|x| !x.is_empty()) {
        let xdg = PathBuf::from(xdg);
        match std::fs::metadata(&xdg) {
            Ok(m) if m.is_dir() && m.uid() == uid() && m.mode() & 0o077 == 0 => {
                return xdg.join("nauta");
            }
            _ => tracing::debug!(
                path = %xdg.display(),
                "XDG_RUNTIME_DIR is not a private directory of this user; using TMPDIR"
            ),
        }
    }
    std::env::temp_dir().join(format!("nauta-{}", uid()))
}

/// The run directory, created (mode 0700) if missing and checked to be
/// private to this user.
pub fn runs_dir() -> Result<PathBuf, RunFileError> {
    let dir = runs_dir_path();
    private_dir(&dir)?;
    Ok(dir)
}

/// Creates `path` (mode 0700) unless it exists, then checks that it is a
/// private directory of this user (see [`check_private_dir`]). Its parent
/// must exist.
pub fn private_dir(path: &Path) -> Result<(), RunFileError> {
    match std::fs::DirBuilder::new().mode(DIR_MODE).create(path) {
        Ok(()) => {
            // The umask may have removed bits; this user just created it.
            std::fs::set_permissions(path, std::os::unix::fs::PermissionsExt::from_mode(DIR_MODE))
                .map_err(|source| RunFileError::Create {
                    path: path.to_owned(),
                    source,
                })?;
        }
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
        Err(source) => {
            return Err(RunFileError::Create {
                path: path.to_owned(),
                source,
            });
        }
    }
    check_private_dir(path)
}

/// Checks, without following a symlink, that `path` is a directory owned by
/// this user with mode exactly 0700.
pub fn check_private_dir(path: &Path) -> Result<(), RunFileError> {
    let m = std::fs::symlink_metadata(path).map_err(|source| RunFileError::Create {
        path: path.to_owned(),
        source,
    })?;
    let why = if m.file_type().is_symlink() {
        Some("it is a symbolic link".to_owned())
    } else if !m.is_dir() {
        Some("it is not a directory".to_owned())
    } else if m.uid() != uid() {
        Some(format!("it is owned by uid {}", m.uid()))
    } else if m.mode() & 0o7777 != DIR_MODE {
        Some(format!("its mode is {:04o}", m.mode() & 0o7777))
    } else {
        None
    };
    match why {
        Some(why) => Err(RunFileError::NotPrivate {
            path: path.to_owned(),
            why,
            uid: uid(),
        }),
        None => Ok(()),
    }
}

/// Creates `path` empty, as [`create_file`] does, and returns it open for writing.
pub fn create_new(path: &Path) -> Result<std::fs::File, RunFileError> {
    open_new(path).map_err(|source| RunFileError::Io {
        path: path.to_owned(),
        source,
    })
}

/// A file name unique on this machine: `{stem}-{pid}-{nanos}-{counter}.{ext}`.
pub fn unique_name(stem: &str, ext: &str) -> String {
    static UNIQUE: AtomicU32 = AtomicU32::new(0);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    format!(
        "{stem}-{}-{nanos:x}-{}.{ext}",
        std::process::id(),
        UNIQUE.fetch_add(1, Ordering::Relaxed)
    )
}

fn open_new(path: &Path) -> std::io::Result<std::fs::File> {
    let f = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(FILE_MODE)
        .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC)
        .open(path)?;
    // Exactly 0600 whatever the umask (on the descriptor: no path is followed).
    f.set_permissions(std::os::unix::fs::PermissionsExt::from_mode(FILE_MODE))?;
    Ok(f)
}

/// Creates `path` with `bytes`: exclusively (an existing file or symlink is
/// an error, never followed or truncated), mode 0600.
pub fn create_file(path: &Path, bytes: &[u8]) -> Result<(), RunFileError> {
    let io = |source| RunFileError::Io {
        path: path.to_owned(),
        source,
    };
    let mut f = open_new(path).map_err(io)?;
    f.write_all(bytes).and_then(|()| f.flush()).map_err(io)
}

/// Replaces `path` with `bytes` atomically: writes a new file created
/// exclusively beside it (mode 0600) and renames it over `path` (rename
/// replaces a symlink, never follows it).
pub fn replace_file(path: &Path, bytes: &[u8]) -> Result<(), RunFileError> {
    static COUNTER: AtomicU32 = AtomicU32::new(0);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(
        ".{name}.{}-{}.tmp",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    create_file(&tmp, bytes)?;
    std::fs::rename(&tmp, path).map_err(|source| {
        let _ = std::fs::remove_file(&tmp);
        RunFileError::Io {
            path: path.to_owned(),
            source,
        }
    })
}

/// Reads `path` (at most `max_bytes`) if it is a regular file owned by this
/// user, without following a symlink.
pub fn read_owned(path: &Path, max_bytes: u64) -> Result<Vec<u8>, RunFileError> {
    let io = |source| RunFileError::Io {
        path: path.to_owned(),
        source,
    };
    let f = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC | libc::O_NONBLOCK)
        .open(path)
        .map_err(|e| {
            if e.raw_os_error() == Some(libc::ELOOP) {
                RunFileError::Untrusted {
                    path: path.to_owned(),
                    why: "it is a symbolic link".into(),
                    uid: uid(),
                }
            } else {
                io(e)
            }
        })?;
    let m = f.metadata().map_err(io)?;
    let why = if !m.is_file() {
        Some("it is not a regular file".to_owned())
    } else if m.uid() != uid() {
        Some(format!("it is owned by uid {}", m.uid()))
    } else if m.len() > max_bytes {
        Some(format!("it holds {} bytes, more than {max_bytes}", m.len()))
    } else {
        None
    };
    if let Some(why) = why {
        return Err(RunFileError::Untrusted {
            path: path.to_owned(),
            why,
            uid: uid(),
        });
    }
    let mut bytes = Vec::new();
    f.take(max_bytes).read_to_end(&mut bytes).map_err(io)?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!(
            "nauta-run-files-{name}-{}-{}",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        private_dir(&d).expect("scratch dir");
        d
    }
    static COUNTER: AtomicU32 = AtomicU32::new(0);

    fn mode(p: &Path) -> u32 {
        std::fs::symlink_metadata(p).expect("stat").mode() & 0o7777
    }

    #[test]
    fn files_are_0600_in_a_0700_directory() {
        let d = scratch("modes");
        assert_eq!(mode(&d), 0o700);
        let f = d.join("a.toml");
        create_file(&f, b"x = 1").expect("create");
        assert_eq!(mode(&f), 0o600);
        replace_file(&f, b"x = 2").expect("replace");
        assert_eq!(mode(&f), 0o600);
        assert_eq!(read_owned(&f, 100).expect("read"), b"x = 2");
        assert!(create_file(&f, b"again").is_err(), "created twice");
        std::fs::remove_dir_all(&d).expect("clean");
    }

    #[test]
    fn a_planted_symlink_is_never_followed() {
        let d = scratch("symlink");
        let target = d.join("victim");
        std::fs::write(&target, b"precious").expect("victim");
        let link = d.join("status.json");
        std::os::unix::fs::symlink(&target, &link).expect("symlink");
        assert!(create_file(&link, b"overwritten").is_err());
        assert!(read_owned(&link, 100).is_err());
        replace_file(&link, b"new").expect("replace");
        assert!(
            !std::fs::symlink_metadata(&link)
                .expect("stat")
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read(&target).expect("victim"), b"precious");
        // A symlink in place of the directory is refused too.
        let dir_link = d.join("dir-link");
        std::os::unix::fs::symlink(&d, &dir_link).expect("symlink");
        assert!(private_dir(&dir_link).is_err());
        std::fs::remove_dir_all(&d).expect("clean");
    }

    #[test]
    fn a_directory_with_another_mode_is_refused() {
        let d = scratch("mode");
        let open = d.join("open");
        std::fs::create_dir(&open).expect("dir");
        std::fs::set_permissions(&open, std::os::unix::fs::PermissionsExt::from_mode(0o755))
            .expect("chmod");
        let e = private_dir(&open).expect_err("0755 accepted");
        assert!(e.to_string().contains("0755"), "{e}");
        std::fs::remove_dir_all(&d).expect("clean");
    }
}
