//! Image sizes on the command line: `WIDTHxHEIGHT`, e.g. `1280x720`.

/// Parses `WxH` (`x` or `X`), each side a whole number of pixels from 1 to `max_side`.
pub fn parse_size(text: &str, max_side: u32) -> Result<(u32, u32), String> {
    let (width, height) = text
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("`{text}` is not a size: expected WIDTHxHEIGHT, e.g. 1280x720"))?;
    let side = |part: &str| -> Result<u32, String> {
        let value: u32 = part
            .trim()
            .parse()
            .map_err(|_| format!("`{part}` in `{text}` is not a whole number of pixels"))?;
        if (1..=max_side).contains(&value) {
            Ok(value)
        } else {
            Err(format!("{value} pixels is out of range: sides must be between 1 and {max_side}"))
        }
    };
    Ok((side(width)?, side(height)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_within_the_limit() {
        assert_eq!(parse_size("1280x720", 4096), Ok((1280, 720)));
        assert_eq!(parse_size("7X3", 4096), Ok((7, 3)));
        assert_eq!(parse_size(" 64 x 32 ", 4096), Ok((64, 32)));
        assert!(parse_size("100000x100000", 4096).expect_err("too big").contains("between 1 and 4096"));
        assert!(parse_size("0x10", 4096).is_err());
        assert!(parse_size("1280", 4096).expect_err("no x").contains("expected WIDTHxHEIGHT"));
        assert!(parse_size("axb", 4096).expect_err("words").contains("not a whole number"));
    }
}
