//! A cursor over a byte slice that never reads out of bounds: every read
//! returns `None` past the end, and callers turn that into a typed error.
//! Varints and zigzag integers follow postcard's wire format (SPEC.md §3.1).

use crate::wire;

#[derive(Clone, Debug)]
pub(crate) struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    pub(crate) const fn new(bytes: &'a [u8]) -> Self {
        Reader { bytes, pos: 0 }
    }

    pub(crate) fn pos(&self) -> usize {
        self.pos
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.pos >= self.bytes.len()
    }

    pub(crate) fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.pos.checked_add(n)?;
        let s = self.bytes.get(self.pos..end)?;
        self.pos = end;
        Some(s)
    }

    /// Everything not read yet; the cursor moves to the end.
    #[cfg_attr(not(feature = "codec-index"), allow(dead_code))]
    pub(crate) fn rest(&mut self) -> &'a [u8] {
        let s = self.bytes.get(self.pos..).unwrap_or(&[]);
        self.pos = self.bytes.len();
        s
    }

    pub(crate) fn u8(&mut self) -> Option<u8> {
        let b = *self.bytes.get(self.pos)?;
        self.pos = self.pos.wrapping_add(1);
        Some(b)
    }

    pub(crate) fn u16_le(&mut self) -> Option<u16> {
        match self.take(2)? {
            [a, b] => Some(u16::from_le_bytes([*a, *b])),
            _ => None,
        }
    }

    pub(crate) fn u32_le(&mut self) -> Option<u32> {
        match self.take(4)? {
            [a, b, c, d] => Some(u32::from_le_bytes([*a, *b, *c, *d])),
            _ => None,
        }
    }

    /// LEB128 varint of at most 5 bytes whose value fits in `u32`
    /// (postcard's `varint(u32)`, SPEC.md §3.1): longer, unterminated or
    /// overflowing encodings fail; over-long ones of at most 5 bytes
    /// (`80 00` for 0) are accepted, as postcard accepts them
    /// ([`wire::varint_u32`]).
    #[inline]
    pub(crate) fn varint_u32(&mut self) -> Option<u32> {
        // One-byte values (most lengths, counts and small numbers) first,
        // here rather than through `wire::varint_u32`: its `(value, next)`
        // result goes through memory, which costs the fast path a stack
        // frame; the rest is a tail call that moves the cursor itself.
        if let Some(&b) = self.bytes.get(self.pos) {
            if b < 0x80 {
                self.pos = self.pos.wrapping_add(1);
                return Some(u32::from(b));
            }
        }
        self.varint_long()
    }

    /// [`Reader::varint_u32`] with its slow path inlined too: for the
    /// `pca-spline` patch scan (a call there costs its loop registers).
    #[cfg(feature = "codec-pca-spline")]
    #[inline(always)]
    pub(crate) fn varint_u32_inline(&mut self) -> Option<u32> {
        let (v, next) = wire::varint_u32_any(self.bytes, self.pos)?;
        self.pos = next;
        Some(v)
    }

    /// [`Reader::varint_u32`] of any length, out of line (inlined, it costs
    /// the M0 `index` path 1.3 %).
    #[inline(never)]
    fn varint_long(&mut self) -> Option<u32> {
        let (v, next) = wire::varint_u32_any(self.bytes, self.pos)?;
        self.pos = next;
        Some(v)
    }

    /// Zigzag-encoded `i32` (postcard's encoding of signed integers).
    pub(crate) fn zigzag_i32(&mut self) -> Option<i32> {
        self.varint_u32().map(wire::zigzag_decode)
    }

    /// A varint length followed by that many bytes (postcard's `&[u8]`).
    pub(crate) fn byte_seq(&mut self) -> Option<&'a [u8]> {
        let len = self.varint_u32()?;
        self.take(usize::try_from(len).ok()?)
    }

    /// A postcard `bool`: exactly 0 or 1.
    pub(crate) fn bool(&mut self) -> Option<bool> {
        match self.u8()? {
            0 => Some(false),
            1 => Some(true),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn varints_follow_postcard() {
        let mut r = Reader::new(&[0x00, 0x7F, 0x80, 0x01, 0xFF, 0xFF, 0xFF, 0xFF, 0x0F]);
        assert_eq!(r.varint_u32(), Some(0));
        assert_eq!(r.varint_u32(), Some(127));
        assert_eq!(r.varint_u32(), Some(128));
        assert_eq!(r.varint_u32(), Some(u32::MAX));
        assert!(r.is_empty());
        // Overflowing fifth byte and unterminated varints are rejected.
        assert_eq!(
            Reader::new(&[0xFF, 0xFF, 0xFF, 0xFF, 0x1F]).varint_u32(),
            None
        );
        assert_eq!(Reader::new(&[0x80, 0x80]).varint_u32(), None);
    }

    /// One test per row of SPEC.md §3.1's canonical-vs-accepted table.
    #[test]
    fn varint_canonical_and_accepted() {
        let read = |b: &[u8]| {
            let mut r = Reader::new(b);
            r.varint_u32().map(|v| (v, r.pos()))
        };
        // Canonical: the shortest form, the only one the encoder writes.
        assert_eq!(read(&[0x00]), Some((0, 1)));
        assert_eq!(read(&[0xAC, 0x02]), Some((300, 2)));
        assert_eq!(read(&[0xFF, 0xFF, 0xFF, 0xFF, 0x0F]), Some((u32::MAX, 5)));
        // Over-long (zero groups at the top) within 5 bytes: accepted.
        assert_eq!(read(&[0x80, 0x00]), Some((0, 2)));
        assert_eq!(read(&[0xAC, 0x82, 0x80, 0x80, 0x00]), Some((300, 5)));
        // Six bytes or more: rejected, even with a value that fits.
        assert_eq!(read(&[0x80, 0x80, 0x80, 0x80, 0x80, 0x00]), None);
        // Fifth byte above 0x0F (the value needs more than 32 bits): rejected.
        assert_eq!(read(&[0xFF, 0xFF, 0xFF, 0xFF, 0x10]), None);
        assert_eq!(read(&[0x80, 0x80, 0x80, 0x80, 0x70]), None);
        // Unterminated at the end of the input: rejected.
        assert_eq!(read(&[0x80]), None);
        assert_eq!(read(&[]), None);
    }

    #[test]
    fn zigzag() {
        let mut r = Reader::new(&[0x00, 0x01, 0x02, 0x03, 0xFE, 0xFF, 0xFF, 0xFF, 0x0F]);
        assert_eq!(r.zigzag_i32(), Some(0));
        assert_eq!(r.zigzag_i32(), Some(-1));
        assert_eq!(r.zigzag_i32(), Some(1));
        assert_eq!(r.zigzag_i32(), Some(-2));
        assert_eq!(r.zigzag_i32(), Some(i32::MAX));
    }
}
