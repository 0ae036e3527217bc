//! Checkpoint files: a header naming the format, the CRC-32 of the body, and the body,
//! MessagePack with named fields of the program version and the state. A checkpoint is
//! read only by the same format and a version not older than its writer's
//! (docs/compatibility.md); a damaged one is refused before its state is read.

use super::error::{RunError, io_err};
use crate::io::atomic::write_atomic;
use serde::Serialize;
use std::path::Path;

/// Header of checkpoint files (format 3): these 8 bytes, the CRC-32 of the body (4 bytes,
/// little endian), then the body: MessagePack with named fields, so a checkpoint stays
/// readable when later versions add fields (with defaults) to the state.
const CHECKPOINT_MAGIC: &[u8; 8] = b"RHEODEM3";
/// Headers of earlier checkpoint formats, recognised to say so.
const OLD_MAGICS: [&[u8; 8]; 1] = [b"RHEODEM2"];

/// The checkpoint file's bytes for `body`.
fn checkpoint_bytes(body: &[u8]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(body.len() + 12);
    bytes.extend_from_slice(CHECKPOINT_MAGIC);
    bytes.extend_from_slice(&crc32fast::hash(body).to_le_bytes());
    bytes.extend_from_slice(body);
    bytes
}

/// Writes `state` atomically as a checkpoint file (header, CRC-32, MessagePack of the
/// program version and the state).
pub fn write_checkpoint<T: Serialize>(path: &Path, state: &T) -> Result<(), RunError> {
    let body =
        rmp_serde::to_vec_named(&(crate::VERSION, state)).map_err(|e| RunError::Checkpoint {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
    write_atomic(path, &checkpoint_bytes(&body)).map_err(io_err("write", path))
}

/// Reads a checkpoint file written by [`write_checkpoint`] in this checkpoint format (the
/// header) by this program version or an earlier one: the state's fields are named, and
/// fields added since take their defaults (docs/compatibility.md). A checkpoint of a newer
/// version is refused before its state is read, since fields this version does not know
/// would be dropped.
pub fn read_checkpoint<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, RunError> {
    let bytes = std::fs::read(path).map_err(io_err("read", path))?;
    let bad = |reason: String| RunError::Checkpoint {
        path: path.to_path_buf(),
        reason,
    };
    let body = checkpoint_body(&bytes).map_err(bad)?;
    let (version, _): (String, serde::de::IgnoredAny) =
        rmp_serde::from_slice(body).map_err(|e| bad(e.to_string()))?;
    if !readable_version(&version) {
        return Err(bad(format!(
            "written by rheodem {version}, newer than this rheodem {}: resume it with that \
             version or a later one",
            crate::VERSION
        )));
    }
    let (_, state): (String, T) = rmp_serde::from_slice(body).map_err(|e| bad(e.to_string()))?;
    Ok(state)
}

/// Whether a checkpoint body written by program `version` (`major.minor.patch`) may be
/// read here: not newer than [`crate::VERSION`].
fn readable_version(version: &str) -> bool {
    let parse = |v: &str| -> Option<Vec<u64>> {
        let core = v.split(['-', '+']).next()?;
        let parts: Option<Vec<u64>> = core.split('.').map(|x| x.parse().ok()).collect();
        parts.filter(|p| p.len() == 3)
    };
    matches!((parse(version), parse(crate::VERSION)), (Some(a), Some(b)) if a <= b)
}

/// The verified body of a checkpoint file, or why it is unusable.
fn checkpoint_body(bytes: &[u8]) -> Result<&[u8], String> {
    if let Some(rest) = bytes.strip_prefix(CHECKPOINT_MAGIC.as_slice()) {
        let (sum, body) = rest
            .split_first_chunk::<4>()
            .ok_or("truncated after its header")?;
        let (stored, actual) = (u32::from_le_bytes(*sum), crc32fast::hash(body));
        if stored != actual {
            return Err(format!(
                "checksum mismatch (stored {stored:08x}, computed {actual:08x}): the file is \
                 damaged; start the run over, or restore the file from a backup"
            ));
        }
        return Ok(body);
    }
    if OLD_MAGICS.iter().any(|m| bytes.starts_with(m.as_slice())) {
        return Err(format!(
            "written in an earlier checkpoint format ({}); this rheodem reads format {} \
             only: start the run over",
            String::from_utf8_lossy(&bytes[..8]),
            String::from_utf8_lossy(CHECKPOINT_MAGIC)
        ));
    }
    Err("missing rheodem checkpoint header".into())
}
