//! The channels a finished file repeats in its summary section, so that the
//! messages of an intact chunk stay readable when the chunk that announced
//! their channel was damaged.
//!
//! A finished MCAP file ends with its summary section (schemas, channels,
//! indexes), a footer record (summary start, summary offset start, summary
//! CRC) and the magic. The summary is used only when its CRC is set and
//! matches (MCAP: the CRC32 of the summary section and of the footer up to
//! and including its summary offset start), and only for channels the data
//! section did not announce itself; a cut file has no summary.

use std::collections::BTreeMap;

use super::records::{self, Record, op};
use super::{Channel, MAGIC, MAX_RECORD_BYTES, Source, Walk};

/// Footer record: opcode, length 20, summary start, summary offset start, CRC.
const FOOTER_BYTES: u64 = records::HEAD_BYTES + 20;

/// The channels of `src`'s summary section, by id; empty when the file has
/// no summary, or one that is damaged.
pub(super) fn channels<S: Source + ?Sized>(
    src: &S,
    file_bytes: u64,
) -> std::io::Result<BTreeMap<u16, Channel>> {
    let none = Ok(BTreeMap::new());
    let Some(footer_at) = file_bytes.checked_sub(FOOTER_BYTES + MAGIC.len() as u64) else {
        return none;
    };
    let mut tail = [0u8; (FOOTER_BYTES as usize) + 8];
    src.read_at(footer_at, &mut tail)?;
    let mut c = records::Cursor::new(&tail);
    let fields = (|| {
        let op = c.bytes(1, "footer opcode")?[0];
        let len = c.u64("footer length")?;
        let start = c.u64("summary start")?;
        c.u64("summary offset start")?;
        let crc = c.u32("summary crc")?;
        Ok::<_, records::RecordError>((op, len, start, crc, c.rest()))
    })();
    let Ok((op::FOOTER, 20, start, crc, magic)) = fields else {
        return none;
    };
    if magic != MAGIC
        || crc == 0
        || !(start >= 8 && start < footer_at)
        || footer_at - start > MAX_RECORD_BYTES
    {
        return none;
    }
    // The summary section and the footer up to its CRC, which covers both.
    let mut summary = vec![0u8; (footer_at - start) as usize + FOOTER_BYTES as usize - 4];
    src.read_at(start, &mut summary)?;
    if crc32fast::hash(&summary) != crc {
        return none;
    }
    let section = &summary[..(footer_at - start) as usize];
    let mut w = Walk {
        rec: Default::default(),
        schemas: BTreeMap::new(),
        on_message: |_: &Channel, _: &super::RecordedMessage<'_>| Ok(()),
        summary: BTreeMap::new(),
    };
    for r in records::split(section) {
        let Ok((opcode @ (op::SCHEMA | op::CHANNEL), body)) = r else {
            continue;
        };
        if let Ok(record @ (Record::Schema { .. } | Record::Channel { .. })) =
            records::parse(opcode, body)
        {
            // Schemas and channels only: `handle` cannot fail on them.
            let _ = w.handle(record);
        }
    }
    Ok(w.rec.channels)
}
