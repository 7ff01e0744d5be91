//! The Portable Float Map (PFM): linear 32-bit float RGB with a three-line text header, read by
//! pbrt, Mitsuba, HDR tools and most image libraries' float paths.
//!
//! Written as `PF\n<width> <height>\n-1.0\n`, then the rows **bottom row first**, each pixel three
//! little-endian `f32`s (the negative scale says little-endian; its magnitude, 1, scales
//! nothing). Read back: colour (`PF`) and grey (`Pf`, spread to three channels), either byte
//! order, the values multiplied by the scale's magnitude when it is not 1 (as pbrt-v4 reads
//! them). A round trip is exact.

use glam::Vec3A;

/// Returns the PFM file of a `width × height` image whose `pixels` are row-major, row 0 at the
/// top.
pub fn encode(width: u32, height: u32, pixels: &[Vec3A]) -> Vec<u8> {
    let header = format!("PF\n{width} {height}\n-1.0\n");
    let mut out = Vec::with_capacity(header.len() + pixels.len() * 12);
    out.extend_from_slice(header.as_bytes());
    for row in pixels.chunks_exact(width.max(1) as usize).rev() {
        for p in row {
            for c in p.to_array() {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    out
}

/// Returns the width, height and pixels (row-major, row 0 at the top) of the PFM file `bytes`,
/// or a message saying what is wrong with it; images of more than `max_pixels` are refused
/// before anything is allocated.
pub fn decode(bytes: &[u8], max_pixels: u64) -> Result<(u32, u32, Vec<Vec3A>), String> {
    let channels = match bytes.get(..2) {
        Some(b"PF") => 3,
        Some(b"Pf") => 1,
        _ => return Err("not a PFM file (it does not start with PF or Pf)".into()),
    };
    let mut at = 2;
    let mut token = || -> Result<&str, String> {
        while bytes.get(at).is_some_and(u8::is_ascii_whitespace) {
            at += 1;
        }
        let start = at;
        while bytes.get(at).is_some_and(|b| !b.is_ascii_whitespace()) {
            at += 1;
        }
        std::str::from_utf8(&bytes[start..at])
            .ok()
            .filter(|t| !t.is_empty())
            .ok_or_else(|| "truncated or malformed PFM header".to_string())
    };
    let width: u32 = parse(token()?, "width")?;
    let height: u32 = parse(token()?, "height")?;
    let scale: f32 = parse(token()?, "scale")?;
    // Exactly one whitespace byte separates the header from the data.
    let data = bytes.get(at + 1..).unwrap_or_default();
    let pixels = width as u64 * height as u64;
    if pixels == 0 || pixels > max_pixels {
        return Err(format!(
            "its header claims {width}x{height} pixels (1 to {max_pixels} are read)"
        ));
    }
    if !(scale.is_finite() && scale != 0.0) {
        return Err(format!("its scale {scale} is not a finite non-zero number"));
    }
    let need = pixels as usize * channels * 4;
    if data.len() < need {
        return Err(format!(
            "truncated: {width}x{height} pixels need {need} bytes of data, the file has {}",
            data.len()
        ));
    }
    let factor = scale.abs();
    let value = |b: &[u8]| {
        let b = [b[0], b[1], b[2], b[3]];
        factor
            * if scale < 0.0 {
                f32::from_le_bytes(b)
            } else {
                f32::from_be_bytes(b)
            }
    };
    let row_bytes = width as usize * channels * 4;
    let mut out = Vec::with_capacity(pixels as usize);
    for row in data[..need].chunks_exact(row_bytes).rev() {
        out.extend(row.chunks_exact(channels * 4).map(|px| {
            let v = |k: usize| value(&px[4 * k..4 * k + 4]);
            if channels == 3 {
                Vec3A::new(v(0), v(1), v(2))
            } else {
                Vec3A::splat(v(0))
            }
        }));
    }
    Ok((width, height, out))
}

/// Returns the header field `text` named `what`, parsed.
fn parse<T: std::str::FromStr>(text: &str, what: &str) -> Result<T, String> {
    text.parse()
        .map_err(|_| format!("its header's {what} '{text}' is not a number"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encodes_bottom_row_first_little_endian_and_round_trips_exactly() {
        let pixels = [
            Vec3A::new(1.0, 2.0, 3.0),
            Vec3A::new(0.1, f32::MIN_POSITIVE, 1e30),
            Vec3A::new(-0.5, 0.0, 7.25),
            Vec3A::new(4.0, 5.0, 6.0),
        ];
        let bytes = encode(2, 2, &pixels);
        let header = b"PF\n2 2\n-1.0\n";
        assert_eq!(&bytes[..header.len()], header);
        // The first pixel stored is the bottom row's first: (-0.5, 0, 7.25).
        assert_eq!(
            &bytes[header.len()..header.len() + 4],
            &(-0.5f32).to_le_bytes()
        );
        assert_eq!(bytes.len(), header.len() + 4 * 12);
        let (w, h, back) = decode(&bytes, 100).unwrap();
        assert_eq!((w, h), (2, 2));
        assert!(
            back.iter()
                .zip(&pixels)
                .all(|(a, b)| a.to_array() == b.to_array())
        );
    }

    #[test]
    fn reads_big_endian_grey_and_scaled_files() {
        let mut bytes = b"Pf\n1 2\n2.0\n".to_vec();
        for v in [3.0f32, 5.0] {
            bytes.extend_from_slice(&v.to_be_bytes());
        }
        let (_, _, px) = decode(&bytes, 100).unwrap();
        // Bottom row first: the top pixel is the second value, times the scale 2.
        assert_eq!(px, vec![Vec3A::splat(10.0), Vec3A::splat(6.0)]);
    }

    #[test]
    fn refuses_malformed_huge_and_truncated_files() {
        let e = |b: &[u8]| decode(b, 1 << 26).unwrap_err();
        assert!(e(b"P6\n1 1\n255\n").contains("not a PFM"));
        assert!(e(b"PF\n1").contains("malformed"));
        assert!(e(b"PF\nx 1\n-1\n").contains("width"));
        assert!(e(b"PF\n100000 100000\n-1\n").contains("claims"));
        assert!(e(b"PF\n0 1\n-1\n").contains("claims"));
        assert!(e(b"PF\n1 1\nnan\n").contains("scale"));
        assert!(e(b"PF\n2 2\n-1\n\0\0\0\0").contains("truncated"));
    }
}
