//! LZF (Marc Lehmann's format), as PCL's `binary_compressed` PCD data uses it. The decoder is
//! complete; the encoder writes a valid stream of literal runs only (no back references),
//! which every LZF decoder, PCL's included, reads.

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

/// Encodes `data` as LZF literal runs (at most 32 bytes each).
pub(crate) fn compress_literal(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len() + data.len() / 32 + 1);
    for chunk in data.chunks(32) {
        out.push((chunk.len() - 1) as u8);
        out.extend_from_slice(chunk);
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

    #[test]
    fn corrupt_streams_name_the_offset() {
        assert_eq!(decompress(&[5, 1, 2], 6).unwrap_err().0, 0);
        assert_eq!(decompress(&[0, 1, (1 << 5), 5], 4).unwrap_err().0, 2);
        assert!(decompress(&[0, 1], 2).is_err());
    }
}
