//! LZF (Marc Lehmann's format), as PCL's `binary_compressed` PCD data uses it: a decoder and
//! a hash-based encoder in the manner of liblzf's `lzf_compress` (the `lzf` crate is
//! deprecated, and the format fits in a page).
//!
//! The stream is a sequence of
//! - literal runs: a byte `L` < 32, then `L + 1` bytes copied as they are;
//! - back references: a byte `LLLooooo` with `LLL` > 0 (length − 2, and 7 means "add the next
//!   byte"), then the low byte of the offset; the `o + 1` bytes before the output's end are
//!   copied `length` times one byte at a time (so a reference may overlap what it writes).

/// The most bytes `n` bytes of LZF can expand to: a 3-byte back reference copies at most
/// 264 bytes (88 per input byte); literals and short references expand less.
pub(crate) fn max_decompressed(n: usize) -> usize {
    n.saturating_mul(88)
}

/// Decompresses `input` into exactly `out_len` bytes. On failure returns the offset in
/// `input` where the stream stopped making sense, and why.
pub(crate) fn decompress(input: &[u8], out_len: usize) -> Result<Vec<u8>, (usize, String)> {
    // The stated size is only trusted as far as the input can expand to it.
    let mut out = Vec::with_capacity(out_len.min(max_decompressed(input.len())));
    let mut i = 0;
    while i < input.len() {
        let at = i;
        let ctrl = input[i] as usize;
        i += 1;
        if ctrl < 32 {
            let len = ctrl + 1;
            if i + len > input.len() {
                return Err((at, format!("literal run of {len} bytes runs past the end")));
            }
            if out.len() + len > out_len {
                return Err((
                    at,
                    format!("data decompresses past the stated {out_len} bytes"),
                ));
            }
            out.extend_from_slice(&input[i..i + len]);
            i += len;
        } else {
            let mut len = ctrl >> 5;
            if len == 7 {
                let Some(&b) = input.get(i) else {
                    return Err((at, "back reference cut off".into()));
                };
                len += b as usize;
                i += 1;
            }
            len += 2;
            let Some(&b) = input.get(i) else {
                return Err((at, "back reference cut off".into()));
            };
            i += 1;
            let back = ((ctrl & 0x1f) << 8) + b as usize + 1;
            if back > out.len() {
                return Err((at, format!("back reference {back} bytes before the start")));
            }
            if out.len() + len > out_len {
                return Err((
                    at,
                    format!("data decompresses past the stated {out_len} bytes"),
                ));
            }
            let start = out.len() - back;
            for k in 0..len {
                let v = out[start + k];
                out.push(v);
            }
        }
    }
    if out.len() != out_len {
        return Err((
            input.len(),
            format!(
                "data decompresses to {} bytes, the header states {out_len}",
                out.len()
            ),
        ));
    }
    Ok(out)
}

/// Encodes `data` as LZF literal runs only (at most 32 bytes each); kept to test the decoder
/// on streams without references.
#[cfg(test)]
pub(crate) fn compress_literal(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len() + data.len() / 32 + 1);
    for chunk in data.chunks(32) {
        out.push((chunk.len() - 1) as u8);
        out.extend_from_slice(chunk);
    }
    out
}

const MAX_LIT: usize = 32;
const MAX_OFF: usize = 1 << 13;
const MAX_REF: usize = (1 << 8) + (1 << 3);
const HLOG: u32 = 16;
const HSIZE: usize = 1 << HLOG;

/// The hash-table slot of the 3 bytes starting at `i` (liblzf's `IDX(FRST/NEXT)`).
#[inline]
fn slot(data: &[u8], i: usize) -> usize {
    let v = ((data[i] as u32) << 16) | ((data[i + 1] as u32) << 8) | data[i + 2] as u32;
    ((v >> (24 - HLOG)).wrapping_sub(v.wrapping_mul(5)) as usize) & (HSIZE - 1)
}

/// Compresses `data` into an LZF stream that [`decompress`] (and liblzf's `lzf_decompress`,
/// which PCL uses) turns back into `data`. Greedy matching over a hash table of the last
/// position of each 3-byte prefix, as liblzf does: a match of 3 to 264 bytes within the last
/// 8 KiB becomes a back reference, everything else literal runs. Never more than
/// `data.len() + data.len() / 32 + 1` bytes.
pub(crate) fn compress(data: &[u8]) -> Vec<u8> {
    let n = data.len();
    let mut out = Vec::with_capacity(n / 2 + 16);
    // Positions + 1 (0: empty slot).
    let mut table = vec![0usize; HSIZE];
    let mut lit = 0usize;
    let mut lit_at = out.len();
    out.push(0);
    let mut ip = 0usize;
    while ip + 2 < n {
        let h = slot(data, ip);
        let r = table[h];
        table[h] = ip + 1;
        let matched = r > 0 && {
            let r = r - 1;
            ip - r - 1 < MAX_OFF && data[r..r + 3] == data[ip..ip + 3]
        };
        if matched {
            let r = r - 1;
            let off = ip - r - 1;
            let maxlen = (n - ip - 2).min(MAX_REF);
            // Close the literal run (or drop its unused length byte).
            if lit == 0 {
                out.pop();
            } else {
                out[lit_at] = (lit - 1) as u8;
            }
            let mut len = 2;
            loop {
                len += 1;
                if len >= maxlen || data[r + len] != data[ip + len] {
                    break;
                }
            }
            // `len` bytes match; stored as len - 2.
            let stored = len - 2;
            if stored < 7 {
                out.push(((off >> 8) + (stored << 5)) as u8);
            } else {
                out.push(((off >> 8) + (7 << 5)) as u8);
                out.push((stored - 7) as u8);
            }
            out.push(off as u8);
            lit = 0;
            lit_at = out.len();
            out.push(0);
            ip += len;
            if ip + 2 >= n {
                break;
            }
            // Enter the two positions before the new one, as liblzf does.
            table[slot(data, ip - 2)] = ip - 1;
            table[slot(data, ip - 1)] = ip;
        } else {
            out.push(data[ip]);
            ip += 1;
            lit += 1;
            if lit == MAX_LIT {
                out[lit_at] = (MAX_LIT - 1) as u8;
                lit = 0;
                lit_at = out.len();
                out.push(0);
            }
        }
    }
    while ip < n {
        out.push(data[ip]);
        ip += 1;
        lit += 1;
        if lit == MAX_LIT {
            out[lit_at] = (MAX_LIT - 1) as u8;
            lit = 0;
            lit_at = out.len();
            out.push(0);
        }
    }
    if lit == 0 {
        out.pop();
    } else {
        out[lit_at] = (lit - 1) as u8;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn literal_round_trip() {
        let data: Vec<u8> = (0..1000u32).map(|i| (i * 7 % 251) as u8).collect();
        let c = compress_literal(&data);
        assert_eq!(decompress(&c, data.len()).unwrap(), data);
        assert_eq!(decompress(&[], 0).unwrap(), Vec::<u8>::new());
    }

    #[test]
    fn back_references() {
        // "abc" literal, then a back reference of length 6 at distance 3: "abcabcabc".
        let c = [2, b'a', b'b', b'c', (4 << 5), 2];
        assert_eq!(decompress(&c, 9).unwrap(), b"abcabcabc");
        // Long form: len field 7 plus an extra byte.
        let c = [0, b'x', (7 << 5), 1, 0];
        assert_eq!(decompress(&c, 11).unwrap(), vec![b'x'; 11]);
    }

    /// Data of the kinds PCL compresses: runs, repeats at every distance, noise, short inputs.
    fn samples() -> Vec<Vec<u8>> {
        let mut v: Vec<Vec<u8>> = vec![
            vec![],
            vec![7],
            vec![1, 2],
            vec![1, 2, 3],
            vec![0; 3],
            vec![0; 4],
            vec![9; 100_000],
            b"abcabcabcabcabcabcabcabcabcabcabcabcabcabcabcabcab".to_vec(),
        ];
        let mut s = 0x2545F4914F6CDD1Du64;
        let mut noise = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s as u8
        };
        v.push((0..70_000).map(|_| noise()).collect());
        // Float columns: smooth coordinates, as in a scan.
        let mut f = Vec::new();
        for i in 0..50_000 {
            f.extend_from_slice(&((i as f32 * 0.001).sin()).to_le_bytes());
        }
        v.push(f);
        // A repeat at the farthest offset and just beyond it.
        for gap in [MAX_OFF - 3, MAX_OFF - 2, MAX_OFF, MAX_OFF + 5] {
            let block: Vec<u8> = (0..300).map(|_| noise()).collect();
            let mut d = block.clone();
            d.extend((0..gap).map(|_| noise()));
            d.extend_from_slice(&block);
            v.push(d);
        }
        v
    }

    #[test]
    fn compress_round_trips_and_compresses() {
        for d in samples() {
            let c = compress(&d);
            assert_eq!(decompress(&c, d.len()).unwrap(), d, "len {}", d.len());
            assert!(c.len() <= d.len() + d.len() / 32 + 1, "len {}", d.len());
        }
        assert!(compress(&[9; 100_000]).len() < 1_500);
        let rep = b"abcabcabcabcabcabcabcabcabcabcabcabcabcabcabcabcab";
        assert!(compress(rep).len() < 16);
    }

    #[test]
    fn corrupt_streams_name_the_offset() {
        assert_eq!(decompress(&[5, 1, 2], 6).unwrap_err().0, 0);
        assert_eq!(decompress(&[0, 1, (1 << 5), 5], 4).unwrap_err().0, 2);
        assert!(decompress(&[0, 1], 2).is_err());
    }
}
