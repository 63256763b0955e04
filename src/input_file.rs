//! Reading the files the package is given (calibration, URDF, scenario TOML, PNG) with bounded
//! cost, and quoting them in errors without leaking their contents.
//!
//! A file is read only if it is a regular file (no device, FIFO, socket or directory) of at
//! most the size limit of its kind. It is opened with `O_NONBLOCK` (a FIFO swapped in after
//! the check cannot block the open), checked with `fstat` on the open descriptor (no race
//! between the check and the read), and read through a reader that stops one byte past the
//! limit (a file that grows meanwhile cannot exhaust memory). Errors name the path and say
//! what is wrong, never what the file contains: values are quoted through [`excerpt`].

use std::fs::File;
use std::io::Read;
use std::path::Path;

/// The largest calibration file, bytes (real ones are a few KB).
pub const MAX_CALIBRATION_BYTES: u64 = 1 << 20;
/// The largest URDF file, bytes (meshes are separate files; the built-in arms are < 20 KB).
pub const MAX_URDF_BYTES: u64 = 8 << 20;
/// The largest scenario file, bytes (about 200,000 object points).
pub const MAX_SCENARIO_BYTES: u64 = 16 << 20;
/// The largest image file, bytes.
pub const MAX_IMAGE_BYTES: u64 = 64 << 20;

/// The longest excerpt of a value that an error quotes, characters.
pub const EXCERPT_CHARS: usize = 16;

/// At most [`EXCERPT_CHARS`] characters of `value`, escaped (control characters and quotes as
/// Rust escapes) and quoted, with `...` and the full length when cut.
pub fn excerpt(value: &str) -> String {
    let n = value.chars().count();
    let head: String = value.chars().take(EXCERPT_CHARS).collect();
    if n <= EXCERPT_CHARS {
        format!("\"{}\"", head.escape_debug())
    } else {
        format!("\"{}...\" ({n} characters)", head.escape_debug())
    }
}

/// Opens `path` for reading without blocking (a FIFO or a device must not hang the open).
fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    options.open(path)
}

/// The bytes of the regular file `path`, at most `limit` of them; the error is a sentence
/// (without the file's contents) for the caller to wrap in its own error variant.
pub(crate) fn read_bytes(path: &Path, limit: u64) -> std::result::Result<Vec<u8>, String> {
    let file = open_nonblocking(path).map_err(|e| format!("cannot read: {e}"))?;
    let meta = file.metadata().map_err(|e| format!("cannot read: {e}"))?;
    if !meta.is_file() {
        return Err("not a regular file (a directory, device, FIFO or socket); give a file".into());
    }
    if meta.len() > limit {
        return Err(format!("{} bytes, more than the limit of {limit} bytes", meta.len()));
    }
    let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0));
    file.take(limit + 1).read_to_end(&mut bytes).map_err(|e| format!("cannot read: {e}"))?;
    if bytes.len() as u64 > limit {
        return Err(format!("more than the limit of {limit} bytes"));
    }
    Ok(bytes)
}

/// The text of the regular file `path` (UTF-8, with an optional byte-order mark), at most
/// `limit` bytes; the error says where the first invalid byte is, not what it is.
pub(crate) fn read_text(path: &Path, limit: u64) -> std::result::Result<String, String> {
    let bytes = read_bytes(path, limit)?;
    String::from_utf8(bytes).map_err(|e| {
        format!(
            "not UTF-8 text (invalid byte at offset {}): a binary file or another encoding (UTF-16, Latin-1)",
            e.utf8_error().valid_up_to()
        )
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn excerpts_are_short_and_escaped() {
        assert_eq!(excerpt("abc"), "\"abc\"");
        let long = "AKIA-0123456789-SECRET";
        let e = excerpt(long);
        assert!(!e.contains("SECRET"), "{e}");
        assert!(e.contains("22 characters"), "{e}");
        assert_eq!(excerpt("a\nb\"\u{1b}"), "\"a\\nb\\\"\\u{1b}\"");
    }

    #[cfg(unix)]
    #[test]
    fn devices_and_large_files_are_refused_quickly() {
        let t = std::time::Instant::now();
        let e = read_bytes(Path::new("/dev/zero"), 1024).unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
        let dir = std::env::temp_dir().join(format!("vsinv-input-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let big = dir.join("big.bin");
        std::fs::write(&big, vec![b'a'; 2000]).unwrap();
        let e = read_bytes(&big, 1000).unwrap_err();
        assert!(e.contains("2000 bytes") && !e.contains("aaa"), "{e}");
        assert_eq!(read_bytes(&big, 2000).unwrap().len(), 2000);
        std::fs::write(&big, [b'x', 0xff, 0xfe]).unwrap();
        let e = read_text(&big, 1000).unwrap_err();
        assert!(e.contains("offset 1"), "{e}");
        let e = read_bytes(&dir, 1000).unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(t.elapsed().as_secs() < 5, "hang test: {:?}", t.elapsed());
    }
}
