//! The node tags of a Gmsh 4.1 `$Nodes` section, in file order.
//!
//! `mshio` keeps node tags only when they are sparse; for a dense range
//! (`max − min + 1 = count`) it drops them, and a reader that then numbers the
//! nodes `min, min + 1, …` in file order misplaces every node of a file whose
//! dense tags are not in order (a renumbered mesh, or one written by another
//! tool). This walks the section once to recover the tags.
//!
//! Layout (4.1): a header `numEntityBlocks numNodes minNodeTag maxNodeTag`,
//! then per block `entityDim entityTag parametric numNodesInBlock`, the block's
//! `numNodesInBlock` tags, then its coordinates (3 per node; parametric nodes
//! are rejected by `mshio` before this is used). ASCII: whitespace-separated
//! numbers. Binary (`4.1 1 <data size>`): `size_t` of the data size for counts
//! and tags, 4-byte ints for the block's first three fields, 8-byte floats,
//! little-endian (the endianness word after the header line is checked).

/// The node tags in file order, `None` when the section cannot be walked
/// (the caller then keeps `mshio`'s reading, which fails on a malformed file).
#[must_use]
pub fn node_tags(bytes: &[u8]) -> Option<Vec<u64>> {
    let (format, after_format) = split_line(after_line(bytes, b"$MeshFormat")?)?;
    let mut words = std::str::from_utf8(format).ok()?.split_whitespace();
    let _version = words.next()?;
    let binary = words.next()? == "1";
    let size_t: usize = words.next()?.parse().ok()?;
    let body = after_line(bytes, b"\n$Nodes")?;
    if binary {
        let one = after_format.get(..4)?;
        if u32::from_le_bytes(one.try_into().ok()?) != 1 {
            return None;
        }
        binary_tags(body, size_t)
    } else {
        ascii_tags(std::str::from_utf8(ascii_prefix(body)).ok()?)
    }
}

/// The bytes after the line holding `marker`.
fn after_line<'a>(bytes: &'a [u8], marker: &[u8]) -> Option<&'a [u8]> {
    let start = bytes.windows(marker.len()).position(|w| w == marker)? + marker.len();
    Some(split_line(&bytes[start..])?.1)
}

/// `(line without its newline, the rest)`.
fn split_line(bytes: &[u8]) -> Option<(&[u8], &[u8])> {
    let newline = bytes.iter().position(|&b| b == b'\n')?;
    Some((&bytes[..newline], &bytes[newline + 1..]))
}

/// The ASCII `$Nodes` body, up to `$EndNodes`.
fn ascii_prefix(body: &[u8]) -> &[u8] {
    let end = body.windows(9).position(|w| w == b"$EndNodes");
    &body[..end.unwrap_or(body.len())]
}

/// The next word as an unsigned integer.
fn int(words: &mut std::str::SplitAsciiWhitespace<'_>) -> Option<u64> {
    words.next()?.parse().ok()
}

fn ascii_tags(text: &str) -> Option<Vec<u64>> {
    let mut words = text.split_ascii_whitespace();
    let blocks = int(&mut words)?;
    let count = usize::try_from(int(&mut words)?).ok()?;
    words.nth(1)?;
    // A tag takes at least two bytes (a digit and a separator): a larger count is not in the
    // file, and reserving it could exhaust memory.
    let mut tags = Vec::with_capacity(count.min(text.len() / 2));
    for _ in 0..blocks {
        words.nth(2)?;
        let n = usize::try_from(int(&mut words)?).ok()?;
        for _ in 0..n {
            tags.push(int(&mut words)?);
        }
        // The coordinates.
        if n > 0 {
            words.nth(n.checked_mul(3)? - 1)?;
        }
    }
    (tags.len() == count).then_some(tags)
}

fn binary_tags(body: &[u8], size_t: usize) -> Option<Vec<u64>> {
    let mut at = 0usize;
    let mut take = |n: usize| -> Option<&[u8]> {
        let s = body.get(at..at.checked_add(n)?)?;
        at += n;
        Some(s)
    };
    let word = |s: &[u8]| -> Option<u64> {
        match s.len() {
            4 => Some(u64::from(u32::from_le_bytes(s.try_into().ok()?))),
            8 => Some(u64::from_le_bytes(s.try_into().ok()?)),
            _ => None,
        }
    };
    let blocks = word(take(size_t)?)?;
    let count = usize::try_from(word(take(size_t)?)?).ok()?;
    take(2 * size_t)?;
    let mut tags = Vec::with_capacity(count.min(body.len() / size_t.max(1)));
    for _ in 0..blocks {
        take(12)?;
        let n = usize::try_from(word(take(size_t)?)?).ok()?;
        for _ in 0..n {
            tags.push(word(take(size_t)?)?);
        }
        take(n.checked_mul(24)?)?;
    }
    (tags.len() == count).then_some(tags)
}
