//! SRTM `.hgt` tiles: no header, `side` x `side` big-endian 16-bit signed heights in metres
//! (1201 a side for 3 arc-seconds, 3601 for 1 arc-second), row 0 the northern edge, -32768 a
//! void. The tile's south-west corner is in its name (`N42E001.hgt`); it spans one degree.

use super::{DemError, Elevation, Spacing};

/// The void value.
pub const VOID: i16 = -32768;

/// The sample count a side of a tile of `length` bytes: 1201 or 3601 (also 3601 x 1801 is not
/// an SRTM size: tiles are square).
pub fn side_of_length(length: usize) -> Option<u32> {
    [1201u32, 3601].into_iter().find(|&side| length == side as usize * side as usize * 2)
}

/// The south-west corner (latitude, longitude in degrees) in a tile's file name, such as
/// `N42E001.hgt` or `s09w078.hgt` (case-insensitive; a folder before it is ignored).
pub fn corner_of_name(name: &str) -> Option<(f64, f64)> {
    let file = name.rsplit(['/', '\\']).next()?;
    let bytes = file.as_bytes();
    if bytes.len() < 7 {
        return None;
    }
    let lat_sign = match bytes[0].to_ascii_uppercase() {
        b'N' => 1.0,
        b'S' => -1.0,
        _ => return None,
    };
    let lon_sign = match bytes[3].to_ascii_uppercase() {
        b'E' => 1.0,
        b'W' => -1.0,
        _ => return None,
    };
    let lat: f64 = file.get(1..3)?.parse().ok()?;
    let lon: f64 = file.get(4..7)?.parse().ok()?;
    (lat <= 90.0 && lon <= 180.0).then_some((lat_sign * lat, lon_sign * lon))
}

/// Reads an SRTM tile from its bytes. Without a corner in `name`, the tile is taken at the
/// equator (a degree of longitude then measures as much as one of latitude), and the reader says
/// nothing: [`corner_of_name`] tells the caller.
pub fn read(bytes: &[u8], name: &str) -> Result<Elevation, DemError> {
    let side = side_of_length(bytes.len()).ok_or_else(|| {
        DemError::new(
            name,
            format!(
                "an SRTM .hgt tile is 1201x1201 or 3601x3601 big-endian 16-bit samples \
                 (2884802 or 25934402 bytes), this file is {} bytes",
                bytes.len()
            ),
        )
    })?;
    let heights = bytes
        .chunks_exact(2)
        .map(|pair| {
            let value = i16::from_be_bytes([pair[0], pair[1]]);
            if value == VOID { f32::NAN } else { f32::from(value) }
        })
        .collect();
    let step = 1.0 / f64::from(side - 1);
    let south = corner_of_name(name).map_or(-0.5, |(lat, _)| lat);
    Ok(Elevation {
        columns: side,
        rows: side,
        heights,
        spacing: Spacing::Degrees { longitude: step, latitude: step, centre_latitude: south + 0.5 },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tile(side: u32, value: impl Fn(u32, u32) -> i16) -> Vec<u8> {
        (0..side * side).flat_map(|i| value(i / side, i % side).to_be_bytes()).collect()
    }

    #[test]
    fn reads_big_endian_samples_and_voids() {
        let bytes = tile(1201, |row, column| if (row, column) == (5, 7) { VOID } else { (row as i16) - 3 });
        let dem = read(&bytes, "some/dir/N42E001.hgt").expect("valid tile");
        assert_eq!((dem.columns, dem.rows), (1201, 1201));
        assert_eq!(dem.heights[0], -3.0);
        assert_eq!(dem.heights[1201 * 1200], 1197.0);
        assert!(dem.heights[5 * 1201 + 7].is_nan());
        let Spacing::Degrees { longitude, centre_latitude, .. } = dem.spacing else { panic!("degrees") };
        assert_eq!(centre_latitude, 42.5);
        assert!((longitude - 3.0 / 3600.0).abs() < 1e-12);
        // At 42.5 N a 3-second column is about 68 m, a row about 92.6 m.
        let (x, y) = dem.spacing.metres().expect("metres");
        assert!((x - 68.3).abs() < 0.3 && (y - 92.6).abs() < 0.2, "{x} {y}");
    }

    #[test]
    fn wrong_lengths_are_refused_with_the_length() {
        let error = read(&[0; 1000], "N00E000.hgt").expect_err("wrong length").to_string();
        assert!(error.starts_with("N00E000.hgt: ") && error.contains("this file is 1000 bytes"), "{error}");
    }

    #[test]
    fn corners_from_names() {
        assert_eq!(corner_of_name("N42E001.hgt"), Some((42.0, 1.0)));
        assert_eq!(corner_of_name("/data/s09W078.HGT"), Some((-9.0, -78.0)));
        assert_eq!(corner_of_name("dem.hgt"), None);
    }
}
