//! Protocol v3's additions to the body (`Documents/Protocol/v3_proposal.md`, and the struct
//! `igtl_extended_header` of the reference library where the proposal's table disagrees):
//!
//! ```text
//! body = extended header | content | metadata header | metadata
//! extended header = ext header size u16 (12) | metadata header size u16 | metadata size u32
//!                   | message id u32
//! metadata header = count u16 | count × (key size u16, value encoding u16, value size u32)
//! metadata        = count × (key bytes, value bytes)
//! ```
//!
//! The metadata header size counts its own 2-byte count; the content size is what the body
//! leaves after the three other parts.

use crate::bytes::{Reader, Writer};
use crate::text::TextEncoding;
use crate::Error;
use heapless::{String, Vec};

/// Bytes of the extended header this codec writes (a longer one received is skipped past).
pub const EXTENDED_HEADER_SIZE: usize = 12;
/// Metadata entries kept per message.
pub const MAX_META_ENTRIES: usize = 8;
/// Bytes of a metadata key kept.
pub const MAX_META_KEY: usize = 32;
/// Bytes of a metadata value kept.
pub const MAX_META_VALUE: usize = 64;

/// One metadata key/value pair.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MetaEntry {
    /// The key (ASCII per the spec).
    pub key: String<MAX_META_KEY>,
    /// How the value is encoded on the wire.
    pub encoding: TextEncoding,
    /// The value.
    pub value: String<MAX_META_VALUE>,
}

/// The bounded key/value metadata of a v3 message.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Metadata {
    entries: Vec<MetaEntry, MAX_META_ENTRIES>,
    dropped: u16,
}

impl Metadata {
    /// No entries.
    pub const fn new() -> Self {
        Metadata {
            entries: Vec::new(),
            dropped: 0,
        }
    }

    /// Sets `key` to `value`, replacing an entry of the same key (the reference library keeps
    /// metadata in a map). `TooLarge` past the bounds, `NotAscii` for a non-ASCII key or an
    /// ASCII-encoded value that is not.
    pub fn insert(&mut self, key: &str, encoding: TextEncoding, value: &str) -> Result<(), Error> {
        TextEncoding::UsAscii.check(key)?;
        encoding.check(value)?;
        let entry = MetaEntry {
            key: String::try_from(key).map_err(|_| Error::TooLarge)?,
            encoding,
            value: String::try_from(value).map_err(|_| Error::TooLarge)?,
        };
        match self.entries.iter_mut().find(|e| e.key == entry.key) {
            Some(old) => *old = entry,
            None => self.entries.push(entry).map_err(|_| Error::TooLarge)?,
        }
        Ok(())
    }

    /// The value of `key`, if present.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.entries
            .iter()
            .find(|e| e.key == key)
            .map(|e| e.value.as_str())
    }

    /// Every entry kept, in the order received or inserted.
    pub fn entries(&self) -> &[MetaEntry] {
        &self.entries
    }

    /// Entries of a received message that were not kept: past [`MAX_META_ENTRIES`], a key or
    /// value too long for the bounds, an encoding other than US-ASCII or UTF-8, or invalid text.
    /// Dropped rather than failing the message, whose content is what a receiver needs.
    pub fn dropped(&self) -> u16 {
        self.dropped
    }

    fn header_size(&self) -> usize {
        2 + 8 * self.entries.len()
    }

    fn data_size(&self) -> usize {
        self.entries
            .iter()
            .map(|e| e.key.len() + e.value.len())
            .sum()
    }

    /// Keeps the entry if it fits; counts it as dropped otherwise.
    fn receive(&mut self, key: &[u8], mib: u16, value: &[u8]) {
        let kept = core::str::from_utf8(key).ok().zip(
            TextEncoding::from_mib(mib)
                .and_then(|enc| enc.decode::<MAX_META_VALUE>(value).map(|v| (enc, v)))
                .ok(),
        );
        let stored = kept.is_some_and(|(k, (enc, v))| self.insert(k, enc, &v).is_ok());
        if !stored {
            self.dropped = self.dropped.saturating_add(1);
        }
    }

    fn decode(header: &[u8], data: &[u8]) -> Result<Self, Error> {
        let mut meta = Metadata::new();
        if header.is_empty() {
            // No metadata header at all: only consistent with no metadata.
            return if data.is_empty() {
                Ok(meta)
            } else {
                Err(Error::Malformed)
            };
        }
        let mut h = Reader::new(header);
        let count = h.u16()?;
        if header.len() != 2 + 8 * usize::from(count) {
            return Err(Error::Malformed);
        }
        let mut d = Reader::new(data);
        for _ in 0..count {
            let key_size = h.u16()?;
            let mib = h.u16()?;
            let value_size = usize::try_from(h.u32()?).map_err(|_| Error::Malformed)?;
            let key = d.take(usize::from(key_size))?;
            let value = d.take(value_size)?;
            meta.receive(key, mib, value);
        }
        if d.remaining() != 0 {
            return Err(Error::Malformed);
        }
        Ok(meta)
    }

    fn encode(&self, w: &mut Writer<'_>) -> Result<(), Error> {
        let count = u16::try_from(self.entries.len()).map_err(|_| Error::TooLarge)?;
        w.u16(count)?;
        for e in &self.entries {
            w.u16(u16::try_from(e.key.len()).map_err(|_| Error::TooLarge)?)?;
            w.u16(e.encoding.mib())?;
            w.u32(u32::try_from(e.value.len()).map_err(|_| Error::TooLarge)?)?;
        }
        for e in &self.entries {
            w.put(e.key.as_bytes())?;
            w.put(e.value.as_bytes())?;
        }
        Ok(())
    }
}

/// What a v3 (header version 2) body carries besides its content.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Extended {
    /// The message id (v3 uses it to pair queries and replies).
    pub message_id: u32,
    /// The key/value metadata.
    pub metadata: Metadata,
}

impl Extended {
    /// Writes the extended header (before the content).
    pub(crate) fn encode_head(&self, w: &mut Writer<'_>) -> Result<(), Error> {
        let header_size =
            u16::try_from(self.metadata.header_size()).map_err(|_| Error::TooLarge)?;
        let data_size = u32::try_from(self.metadata.data_size()).map_err(|_| Error::TooLarge)?;
        w.u16(EXTENDED_HEADER_SIZE as u16)?;
        w.u16(header_size)?;
        w.u32(data_size)?;
        w.u32(self.message_id)
    }

    /// Writes the metadata header and metadata (after the content).
    pub(crate) fn encode_tail(&self, w: &mut Writer<'_>) -> Result<(), Error> {
        self.metadata.encode(w)
    }

    /// Splits a v3 body into its extended part and its content.
    pub(crate) fn split(body: &[u8]) -> Result<(Extended, &[u8]), Error> {
        let mut r = Reader::new(body);
        let ext_size = usize::from(r.u16()?);
        let meta_header_size = usize::from(r.u16()?);
        let meta_size = usize::try_from(r.u32()?).map_err(|_| Error::Malformed)?;
        let message_id = r.u32()?;
        let tail = meta_header_size
            .checked_add(meta_size)
            .ok_or(Error::Malformed)?;
        let content_end = body.len().checked_sub(tail).ok_or(Error::Malformed)?;
        if ext_size < EXTENDED_HEADER_SIZE || ext_size > content_end {
            return Err(Error::Malformed);
        }
        let (front, meta) = body.split_at(content_end);
        let (meta_header, meta_data) = meta.split_at(meta_header_size);
        let metadata = Metadata::decode(meta_header, meta_data)?;
        Ok((
            Extended {
                message_id,
                metadata,
            },
            &front[ext_size..],
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn insert_replaces_and_bounds() {
        let mut m = Metadata::new();
        m.insert("TransformStatus", TextEncoding::UsAscii, "OK")
            .unwrap();
        m.insert("TransformStatus", TextEncoding::UsAscii, "INVALID")
            .unwrap();
        assert_eq!(m.entries().len(), 1);
        assert_eq!(m.get("TransformStatus"), Some("INVALID"));
        assert_eq!(
            m.insert("k", TextEncoding::UsAscii, "é"),
            Err(Error::NotAscii)
        );
        m.insert("k", TextEncoding::Utf8, "é").unwrap();
        let long = "x".repeat(MAX_META_VALUE + 1);
        assert_eq!(
            m.insert("k", TextEncoding::Utf8, &long),
            Err(Error::TooLarge)
        );
        for i in 0..MAX_META_ENTRIES - 2 {
            m.insert(&format!("key{i}"), TextEncoding::UsAscii, "v")
                .unwrap();
        }
        assert_eq!(
            m.insert("one more", TextEncoding::UsAscii, "v"),
            Err(Error::TooLarge)
        );
    }

    #[test]
    fn received_entries_that_do_not_fit_are_counted_not_fatal() {
        // count 3: a good one, one with encoding 4 (ISO-8859-1), one whose value is too long.
        let long = [b'v'; MAX_META_VALUE + 1];
        let mut header = std::vec![0, 3];
        for (k, enc, v) in [(2u16, 3u16, 2u32), (1, 4, 1), (1, 3, long.len() as u32)] {
            header.extend_from_slice(&k.to_be_bytes());
            header.extend_from_slice(&enc.to_be_bytes());
            header.extend_from_slice(&v.to_be_bytes());
        }
        let mut data = std::vec::Vec::from(&b"okyeazk"[..]);
        data.extend_from_slice(&long);
        let m = Metadata::decode(&header, &data).unwrap();
        assert_eq!(m.get("ok"), Some("ye"));
        assert_eq!(m.entries().len(), 1);
        assert_eq!(m.dropped(), 2);
        // Sizes that disagree with the data are malformed, not dropped.
        assert_eq!(Metadata::decode(&header, &data[1..]), Err(Error::Malformed));
        assert_eq!(Metadata::decode(&header[..9], &data), Err(Error::Malformed));
        assert_eq!(Metadata::decode(&[], b"x"), Err(Error::Malformed));
    }

    #[test]
    fn split_finds_the_content_between_header_and_metadata() {
        let mut ext = Extended {
            message_id: 77,
            metadata: Metadata::new(),
        };
        ext.metadata
            .insert("Status", TextEncoding::Utf8, "OK")
            .unwrap();
        let mut buf = [0u8; 64];
        let mut w = Writer::new(&mut buf);
        ext.encode_head(&mut w).unwrap();
        w.put(b"CONTENT").unwrap();
        ext.encode_tail(&mut w).unwrap();
        let n = w.len();
        assert_eq!(n, 12 + 7 + 10 + 8);
        assert_eq!(&buf[..12], &[0, 12, 0, 10, 0, 0, 0, 8, 0, 0, 0, 77]);
        let (back, content) = Extended::split(&buf[..n]).unwrap();
        assert_eq!(content, b"CONTENT");
        assert_eq!(back, ext);
        assert_eq!(Extended::split(&buf[..11]), Err(Error::Malformed));
        assert_eq!(Extended::split(&buf[..n - 1]), Err(Error::Malformed));
    }
}
