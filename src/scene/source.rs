//! A scene file's text as the app keeps it for save-back ([`Source`]):
//! whole when small; when large, in blocks of [`BLOCK_BYTES`] each
//! compressed on its own (zstd, its fastest level), so that a million
//! spheres' 214 MB of XML is held in about 21 MB, and read back a block at
//! a time, in order ([`Source::reader`]) or whole ([`Source::text`]) where
//! a use needs it. An editor's text of the file is compared with it a
//! block at a time, on the cores ([`Source::is_near`], [`Source::difference`]).
//!
//! The text is held, not read again from the file, because the file may
//! have changed since (another program's save, to be merged with the
//! edits), and undoing a reload brings back a text the file no longer has.

use std::borrow::Cow;
use std::io::Read;
use std::sync::Arc;

use rayon::prelude::*;

/// Texts from this size on are held in compressed blocks.
pub const PACK_BYTES: usize = 16 << 20;

/// About the size of a compressed block's text: big enough to compress
/// well, small enough that reading one back for a piece of it is quick.
pub const BLOCK_BYTES: usize = 1 << 20;

/// zstd's level: its fastest.
const LEVEL: i32 = 1;

/// A scene file's text, shared: copies share one held text.
#[derive(Clone)]
pub struct Source(Arc<Held>);

enum Held {
    Whole(String),
    /// The text's blocks in order, each compressed on its own.
    Packed {
        blocks: Vec<Block>,
        len: usize,
    },
}

/// A piece of a packed text, compressed (it may end inside a character).
pub struct Block {
    packed: Box<[u8]>,
    /// The length of its text.
    len: usize,
}

impl Block {
    /// Packs `text`, a piece of a text.
    pub fn pack(text: &[u8]) -> Block {
        thread_local! {
            // One compressor a thread, its tables made once.
            static PACKER: std::cell::RefCell<Option<zstd::bulk::Compressor<'static>>> =
                const { std::cell::RefCell::new(None) };
        }
        let packed = PACKER
            .with_borrow_mut(|packer| {
                let packer = match packer {
                    Some(packer) => packer,
                    None => packer.insert(zstd::bulk::Compressor::new(LEVEL)?),
                };
                packer.compress(text)
            })
            .expect("a block of text packs");
        Block {
            packed: packed.into_boxed_slice(),
            len: text.len(),
        }
    }

    fn unpack(&self) -> Vec<u8> {
        let mut text = vec![0; self.len];
        self.unpack_into(&mut text);
        text
    }

    /// Unpacks the block into `text`, as long as its text.
    fn unpack_into(&self, text: &mut [u8]) {
        thread_local! {
            static UNPACKER: std::cell::RefCell<Option<zstd::bulk::Decompressor<'static>>> =
                const { std::cell::RefCell::new(None) };
        }
        let unpacked = UNPACKER
            .with_borrow_mut(|unpacker| {
                let unpacker = match unpacker {
                    Some(unpacker) => unpacker,
                    None => unpacker.insert(zstd::bulk::Decompressor::new()?),
                };
                unpacker.decompress_to_buffer(&self.packed, text)
            })
            .expect("a packed block unpacks");
        assert_eq!(unpacked, self.len, "a packed block unpacks whole");
    }
}

impl std::fmt::Debug for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &*self.0 {
            Held::Whole(text) => write!(f, "Source({} bytes)", text.len()),
            Held::Packed { len, .. } => {
                write!(f, "Source({len} bytes in {} packed)", self.held_bytes())
            }
        }
    }
}

impl Default for Source {
    /// The empty text.
    fn default() -> Source {
        Source::new(String::new())
    }
}

impl Source {
    /// Holds `text`: packed (on the cores) when it has [`PACK_BYTES`] or
    /// more, its own memory freed.
    pub fn new(text: String) -> Source {
        if text.len() < PACK_BYTES {
            return Source(Arc::new(Held::Whole(text)));
        }
        Source::packed(&text)
    }

    /// Holds `text` packed whatever its size, in blocks of [`BLOCK_BYTES`]
    /// (tests and tools that check a packed text against the same text
    /// held whole).
    pub fn packed(text: &str) -> Source {
        Source::from_blocks(
            text.as_bytes()
                .par_chunks(BLOCK_BYTES)
                .map(Block::pack)
                .collect(),
        )
    }

    /// The text whose pieces, in order, `blocks` packed ([`Block::pack`]).
    /// Together they must be UTF-8 (the loader checks each piece, cut
    /// between two elements, before it packs it).
    pub fn from_blocks(blocks: Vec<Block>) -> Source {
        let len = blocks.iter().map(|b| b.len).sum();
        Source(Arc::new(Held::Packed { blocks, len }))
    }

    /// The text's length in bytes.
    pub fn len(&self) -> usize {
        match &*self.0 {
            Held::Whole(text) => text.len(),
            Held::Packed { len, .. } => *len,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the text is held in compressed blocks.
    pub fn is_packed(&self) -> bool {
        matches!(&*self.0, Held::Packed { .. })
    }

    /// The bytes held for it.
    pub fn held_bytes(&self) -> usize {
        match &*self.0 {
            Held::Whole(text) => text.len(),
            Held::Packed { blocks, .. } => blocks.iter().map(|b| b.packed.len()).sum(),
        }
    }

    /// The text, when it is held whole.
    pub fn as_str(&self) -> Option<&str> {
        match &*self.0 {
            Held::Whole(text) => Some(text),
            Held::Packed { .. } => None,
        }
    }

    /// Both are the one held text.
    pub fn same(&self, other: &Source) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }

    /// The whole text: borrowed when held whole, else unpacked, its
    /// blocks on the cores (as big as the text: for the uses that need it
    /// whole, not for a save).
    pub fn text(&self) -> Cow<'_, str> {
        match &*self.0 {
            Held::Whole(text) => Cow::Borrowed(text),
            Held::Packed { blocks, len } => {
                let mut bytes = vec![0; *len];
                let mut rest = bytes.as_mut_slice();
                let mut pieces = Vec::with_capacity(blocks.len());
                for block in blocks {
                    let (piece, after) = rest.split_at_mut(block.len);
                    pieces.push((block, piece));
                    rest = after;
                }
                pieces
                    .into_par_iter()
                    .for_each(|(block, piece)| block.unpack_into(piece));
                // It was UTF-8 when packed.
                Cow::Owned(String::from_utf8(bytes).expect("a packed text is UTF-8"))
            }
        }
    }

    /// Whether the text is `text`, compared a block at a time, the block
    /// holding byte `at` first: where a text was just edited there, a
    /// packed text is told apart from it by unpacking one block, not all
    /// before it.
    pub fn is_near(&self, text: &str, at: usize) -> bool {
        if text.len() != self.len() {
            return false;
        }
        match &*self.0 {
            Held::Whole(own) => own == text,
            Held::Packed { blocks, .. } => {
                let mut start = 0;
                let pieces: Vec<(&Block, &[u8])> = blocks
                    .iter()
                    .map(|block| {
                        let end = (start + block.len).min(text.len());
                        let piece = (block, &text.as_bytes()[start..end]);
                        start = end;
                        piece
                    })
                    .collect();
                let near = pieces
                    .iter()
                    .scan(0, |end, (block, _)| {
                        *end += block.len;
                        Some(*end)
                    })
                    .position(|end| at < end)
                    .unwrap_or(0);
                let same = |(block, theirs): &(&Block, &[u8])| block.unpack() == *theirs;
                pieces.get(near).is_none_or(same) && pieces.iter().all(same)
            }
        }
    }

    /// The text's bytes `range` (cut to the text's end), unpacking only
    /// the blocks that hold them.
    pub fn bytes(&self, range: std::ops::Range<usize>) -> Cow<'_, [u8]> {
        let end = range.end.min(self.len());
        let start = range.start.min(end);
        match &*self.0 {
            Held::Whole(text) => Cow::Borrowed(&text.as_bytes()[start..end]),
            Held::Packed { blocks, .. } => {
                let mut bytes = Vec::with_capacity(end - start);
                let mut at = 0;
                for block in blocks {
                    let next = at + block.len;
                    if next > start && at < end {
                        let text = block.unpack();
                        bytes.extend_from_slice(&text[start.max(at) - at..end.min(next) - at]);
                    }
                    if next >= end {
                        break;
                    }
                    at = next;
                }
                Cow::Owned(bytes)
            }
        }
    }

    /// Where `text` differs from this text: the bytes of this text
    /// between the longest prefix and the longest suffix the two share
    /// (on characters' boundaries), and the length of what replaces them
    /// in `text`; `None` where they are the same. A packed text is
    /// unpacked on the cores, a block at a time.
    pub fn difference(&self, text: &str) -> Option<(std::ops::Range<usize>, usize)> {
        let (own_len, len) = (self.len(), text.len());
        let theirs = text.as_bytes();
        // `text` against this text's bytes `own`, starting at `start`:
        // the first that differs, aligned at the start, and the last,
        // aligned at the end (a byte with nothing across differs).
        let shift = len as isize - own_len as isize;
        let compare = |start: usize, own: &[u8]| {
            let across = theirs
                .get(start.min(len)..(start + own.len()).min(len))
                .unwrap_or_default();
            let front = first_difference(own, across).map(|i| start + i);
            let lo = usize::try_from(-(start as isize + shift)).unwrap_or(0);
            let from = (start as isize + shift).max(0) as usize;
            let window = theirs.get(from..from + own.len().saturating_sub(lo));
            let back = match own.get(lo..).zip(window) {
                Some((own_end, window)) => match last_difference(own_end, window) {
                    Some(j) => Some(lo + j),
                    None => lo.checked_sub(1),
                },
                None => own.len().checked_sub(1),
            }
            .map(|j| start + j);
            (front, back)
        };
        let found: Vec<(Option<usize>, Option<usize>)> = match &*self.0 {
            Held::Whole(own) => vec![compare(0, own.as_bytes())],
            Held::Packed { blocks, .. } => {
                let starts = blocks.iter().scan(0, |at, block| {
                    let start = *at;
                    *at += block.len;
                    Some(start)
                });
                let pieces: Vec<(usize, &Block)> = starts.zip(blocks).collect();
                pieces
                    .par_iter()
                    .map(|(start, block)| compare(*start, &block.unpack()))
                    .collect()
            }
        };
        let shortest = own_len.min(len);
        let mut prefix = found.iter().find_map(|(f, _)| *f).unwrap_or(shortest);
        let last = found.iter().rev().find_map(|(_, b)| *b);
        let mut suffix = last.map_or(shortest, |j| own_len - j - 1);
        if prefix == shortest && suffix == shortest && own_len == len {
            return None;
        }
        prefix = prefix.min(shortest);
        suffix = suffix.min(shortest - prefix);
        while !text.is_char_boundary(prefix) {
            prefix -= 1;
        }
        while !text.is_char_boundary(len - suffix) {
            suffix -= 1;
        }
        Some((prefix..own_len - suffix, len - suffix - prefix))
    }

    /// The text's bytes in order, a block unpacked at a time.
    pub fn reader(&self) -> SourceReader<'_> {
        SourceReader {
            source: self,
            block: 0,
            current: Vec::new(),
            at: 0,
        }
    }
}

/// Where `a` and `b` first differ (a byte with nothing across differs);
/// `None` where they are the same. Compared in chunks (memcmp's speed).
fn first_difference(a: &[u8], b: &[u8]) -> Option<usize> {
    const CHUNK: usize = 64;
    let n = a.len().min(b.len());
    let mut at = 0;
    while at + CHUNK <= n && a[at..at + CHUNK] == b[at..at + CHUNK] {
        at += CHUNK;
    }
    match a[at..n].iter().zip(&b[at..n]).position(|(x, y)| x != y) {
        Some(i) => Some(at + i),
        None => (a.len() != b.len()).then_some(n),
    }
}

/// Where `a` and `b`, of one length, last differ; `None` where they are
/// the same.
fn last_difference(a: &[u8], b: &[u8]) -> Option<usize> {
    const CHUNK: usize = 64;
    let mut end = a.len().min(b.len());
    while end >= CHUNK && a[end - CHUNK..end] == b[end - CHUNK..end] {
        end -= CHUNK;
    }
    (0..end).rev().find(|&i| a[i] != b[i])
}

/// A [`Source`]'s bytes in order ([`Source::reader`]).
pub struct SourceReader<'s> {
    source: &'s Source,
    /// The next block to unpack.
    block: usize,
    /// The block unpacked last.
    current: Vec<u8>,
    /// How much of `current` (of a whole text: of the text) was read.
    at: usize,
}

impl Read for SourceReader<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let rest: &[u8] = match &*self.source.0 {
            // A whole text is read in place.
            Held::Whole(text) => &text.as_bytes()[self.at..],
            Held::Packed { blocks, .. } => {
                while self.at == self.current.len() {
                    let Some(block) = blocks.get(self.block) else {
                        return Ok(0);
                    };
                    self.current = block.unpack();
                    self.block += 1;
                    self.at = 0;
                }
                &self.current[self.at..]
            }
        };
        let n = rest.len().min(buf.len());
        buf[..n].copy_from_slice(&rest[..n]);
        self.at += n;
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn big() -> String {
        let mut text = String::from("<scene>\n");
        let mut k = 0u64;
        while text.len() < PACK_BYTES + BLOCK_BYTES / 3 {
            k += 1;
            // Characters of 2, 3 and 4 bytes, some across block ends.
            text.push_str(&format!("  <!-- é€𝄞 {k} --><sphere/>\n"));
        }
        text.push_str("</scene>\n");
        text
    }

    /// `text` packed in blocks of `sizes` bytes in turn (moved on to a
    /// character's end), so that edits fall across their ends.
    fn packed_in(text: &str, sizes: &[usize]) -> Source {
        let mut blocks = Vec::new();
        let mut rest = text;
        for n in sizes.iter().cycle() {
            if rest.is_empty() {
                break;
            }
            let mut cut = (*n).min(rest.len());
            while !rest.is_char_boundary(cut) {
                cut += 1;
            }
            blocks.push(Block::pack(&rest.as_bytes()[..cut]));
            rest = &rest[cut..];
        }
        Source::from_blocks(blocks)
    }

    /// Whether `source` holds `text`.
    fn holds(source: &Source, text: &str) -> bool {
        source.is_near(text, 0)
    }

    #[test]
    fn a_large_text_is_packed_and_reads_back_the_same() {
        let text = big();
        let source = Source::new(text.clone());
        assert!(source.is_packed());
        assert!(source.held_bytes() < text.len() / 4, "{source:?}");
        assert_eq!(source.len(), text.len());
        assert_eq!(source.text(), text);
        assert!(holds(&source, &text));
        let mut other = text.clone().into_bytes();
        let last = other.len() - 2;
        other[last] = b'X';
        assert!(!holds(&source, std::str::from_utf8(&other).unwrap()));
        assert!(!holds(&source, &text[1..]));
        // Read in odd sizes.
        let mut reader = source.reader();
        let mut back = Vec::new();
        let mut buf = [0u8; 77_777];
        loop {
            let n = reader.read(&mut buf).unwrap();
            if n == 0 {
                break;
            }
            back.extend_from_slice(&buf[..n]);
        }
        assert_eq!(back, text.as_bytes());
    }

    #[test]
    fn blocks_of_any_size_make_the_text_they_packed() {
        let text = big();
        let source = packed_in(&text, &[1, 17, 0, 65_536, 3_000_001]);
        // Any piece, across blocks' ends or past the text's.
        let n = text.len();
        for range in [
            0..0,
            0..1,
            1..19,
            17..70_000,
            n / 2..n / 2 + 5_000_000,
            n - 3..n + 9,
        ] {
            let want = &text.as_bytes()[range.start.min(n)..range.end.min(n)];
            assert_eq!(&*source.bytes(range.clone()), want, "{range:?}");
        }
        assert_eq!(source.len(), text.len());
        assert!(holds(&source, &text));
        assert_eq!(source.text(), text);
        assert!(!holds(
            &source,
            &text.replace("<sphere/>\n</scene>", "<sphere/>\n</scenE>")
        ));
    }

    #[test]
    fn a_small_text_is_held_whole() {
        let source = Source::new("<scene/>".to_owned());
        assert!(!source.is_packed());
        assert!(matches!(source.text(), Cow::Borrowed("<scene/>")));
        let mut back = String::new();
        source.reader().read_to_string(&mut back).unwrap();
        assert_eq!(back, "<scene/>");
        assert!(holds(&source, "<scene/>") && !holds(&source, "<scene />"));
        assert!(source.same(&source.clone()));
        assert!(!source.same(&Source::new("<scene/>".to_owned())));
    }

    /// What differs between two texts, counted naively: the common
    /// prefix, then the common suffix of what is left, on characters'
    /// boundaries.
    fn naive(own: &str, text: &str) -> Option<(std::ops::Range<usize>, usize)> {
        if own == text {
            return None;
        }
        let (a, b) = (own.as_bytes(), text.as_bytes());
        let mut prefix = a.iter().zip(b).take_while(|(x, y)| x == y).count();
        while !text.is_char_boundary(prefix) {
            prefix -= 1;
        }
        let room = a.len().min(b.len()) - prefix;
        let mut suffix = (a.iter().rev().zip(b.iter().rev()))
            .take_while(|(x, y)| x == y)
            .count()
            .min(room);
        while !text.is_char_boundary(b.len() - suffix) {
            suffix -= 1;
        }
        Some((prefix..a.len() - suffix, b.len() - suffix - prefix))
    }

    /// Edits anywhere (ends, block ends, inside characters of several
    /// bytes, a text grown or cut short): the difference found a block at a
    /// time is the one counted naively, held whole or packed.
    #[test]
    fn the_difference_is_the_span_between_the_common_ends() {
        let text = big();
        let packed = packed_in(&text, &[1, 65_536, 3_000_001, 777]);
        let sources = [packed, Source::new(text.clone())];
        let n = text.len();
        let mut cases: Vec<String> = vec![text.clone(), String::new(), format!("{text}x")];
        cases.push(format!("x{text}"));
        cases.push(text[..n / 2].to_owned());
        cases.push(text[n / 3..].to_owned());
        for at in [0, 1, 65_536, 65_537, n / 2, n - 9, n - 1, n] {
            let mut at = at;
            while !text.is_char_boundary(at) {
                at -= 1;
            }
            for (cut, put) in [(0, "é"), (1, ""), (3, "𝄞𝄞"), (70, "<sphere/>"), (0, "")] {
                let mut end = (at + cut).min(n);
                while !text.is_char_boundary(end) {
                    end += 1;
                }
                let mut edited = text.clone();
                edited.replace_range(at..end, put);
                cases.push(edited);
            }
        }
        // An edit inside a character: `é` (c3 a9) to `ê` (c3 aa).
        cases.push(text.replacen("é", "ê", 1));
        for source in &sources {
            for case in &cases {
                let found = source.difference(case);
                assert_eq!(found, naive(&text, case), "{} bytes", case.len());
                if let Some((range, put)) = found {
                    let mut back = text.clone();
                    back.replace_range(range.clone(), &case[range.start..range.start + put]);
                    assert_eq!(&back, case);
                }
            }
        }
    }
}
