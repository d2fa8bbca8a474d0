//! Strict number parsing for attribute values, and Mitsuba's list tokenizer.

/// The tokens of a list attribute: separated by commas and white space, empty tokens skipped
/// (Mitsuba's `string::tokenize`).
pub fn tokens(text: &str) -> impl Iterator<Item = &str> {
    text.split(|c: char| c == ',' || c.is_whitespace()).filter(|t| !t.is_empty())
}

/// A finite number: decimal with optional sign, fraction and exponent, white space around it
/// allowed. `inf`, `nan`, hexadecimal and trailing text are refused.
pub fn float(text: &str) -> Option<f64> {
    let t = text.trim();
    // Rust also accepts "inf", "infinity" and "nan": only digits, signs, '.', 'e' pass here.
    if t.is_empty() || !t.bytes().all(|b| b.is_ascii_digit() || matches!(b, b'+' | b'-' | b'.' | b'e' | b'E'))
    {
        return None;
    }
    t.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// A signed 64-bit integer in decimal, white space around it allowed.
pub fn integer(text: &str) -> Option<i64> {
    text.trim().parse::<i64>().ok()
}

/// `true` or `false`, in any case, white space around it allowed (Mitsuba compares without
/// case).
pub fn boolean(text: &str) -> Option<bool> {
    let t = text.trim();
    if t.eq_ignore_ascii_case("true") {
        Some(true)
    } else if t.eq_ignore_ascii_case("false") {
        Some(false)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_parse_strictly() {
        assert_eq!(float(" 1.5e2 "), Some(150.0));
        assert_eq!(float("-.5"), Some(-0.5));
        for bad in ["", "1.5x", "inf", "NaN", "1e999", "0x10", "1 2", "--1"] {
            assert_eq!(float(bad), None, "{bad:?}");
        }
        assert_eq!(integer(" -42 "), Some(-42));
        for bad in ["", "1.0", "1e3", "99999999999999999999", "4x"] {
            assert_eq!(integer(bad), None, "{bad:?}");
        }
        assert_eq!(boolean("TRUE"), Some(true));
        assert_eq!(boolean("False"), Some(false));
        assert_eq!(boolean("1"), None);
    }

    #[test]
    fn lists_split_on_commas_and_spaces() {
        let t: Vec<_> = tokens(" 1, 2 ,3\t4,,5 ").collect();
        assert_eq!(t, ["1", "2", "3", "4", "5"]);
    }
}
