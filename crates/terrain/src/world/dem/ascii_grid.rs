//! Esri ASCII grids (`.asc`): a header of `ncols`, `nrows`, `xllcorner` or `xllcenter`,
//! `yllcorner` or `yllcenter`, `cellsize` and an optional `NODATA_value`, then `nrows` rows of
//! `ncols` numbers from the northern row. The format states no coordinate system: a grid whose
//! cell size is under 0.01 and whose corner lies within ±180, ±90 is taken as geographic
//! (degrees), anything else as metres.

use super::{DemError, Elevation, SizeLimit, Spacing};

/// Whether `bytes` start like an ASCII grid's header (`ncols`, `nrows`, ... as the first word).
pub fn looks_like(bytes: &[u8]) -> bool {
    let start = bytes.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(bytes.len());
    let head = &bytes[start..bytes.len().min(start + 9)];
    ["ncols", "nrows", "xllcorner", "xllcenter", "yllcorner", "yllcenter"]
        .iter()
        .any(|key| head.len() >= key.len() && head[..key.len()].eq_ignore_ascii_case(key.as_bytes()))
}

/// Reads an ASCII grid from its bytes. Errors name the file and the line (and the row) at fault.
pub fn read(bytes: &[u8], name: &str, limit: SizeLimit) -> Result<Elevation, DemError> {
    let text = std::str::from_utf8(bytes).map_err(|error| {
        DemError::new(
            name,
            format!("not an ASCII grid: the text is not UTF-8 (at byte {})", error.valid_up_to()),
        )
    })?;
    let mut lines = text.lines().enumerate().peekable();
    let mut header = Header::default();
    // Header lines: a key and a value, until the first line that starts with a number.
    while let Some(&(index, line)) = lines.peek() {
        let mut words = line.split_whitespace();
        let Some(key) = words.next() else {
            lines.next();
            continue;
        };
        if key.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '+' || c == '.') {
            break;
        }
        let line_number = index + 1;
        let value = words
            .next()
            .ok_or_else(|| DemError::new(name, format!("line {line_number}: `{key}` has no value")))?;
        let number: f64 = value.parse().map_err(|_| {
            DemError::new(
                name,
                format!("line {line_number}: the value of `{key}`, `{value}`, is not a number"),
            )
        })?;
        match key.to_ascii_lowercase().as_str() {
            "ncols" => header.columns = Some(whole(number, key, line_number, name)?),
            "nrows" => header.rows = Some(whole(number, key, line_number, name)?),
            "xllcorner" => header.x = Some((number, false)),
            "xllcenter" => header.x = Some((number, true)),
            "yllcorner" => header.y = Some((number, false)),
            "yllcenter" => header.y = Some((number, true)),
            "cellsize" => header.cell = Some((number, number)),
            "dx" => header.cell = Some((number, header.cell.map_or(number, |c| c.1))),
            "dy" => header.cell = Some((header.cell.map_or(number, |c| c.0), number)),
            "nodata_value" => header.nodata = Some(number),
            other => {
                return Err(DemError::new(name, format!("line {line_number}: unknown header key `{other}`")));
            }
        }
        lines.next();
    }
    let missing = |key: &str| DemError::new(name, format!("the header has no `{key}`"));
    let columns = header.columns.ok_or_else(|| missing("ncols"))?;
    let rows = header.rows.ok_or_else(|| missing("nrows"))?;
    let (cell_x, cell_y) = header.cell.ok_or_else(|| missing("cellsize"))?;
    limit.check(name, columns, rows)?;
    let count = columns * rows;
    // Every number takes at least two bytes (a digit and a separator): refuse a lying header
    // before allocating for it.
    if count > bytes.len() as u64 / 2 + 1 {
        return Err(DemError::new(
            name,
            format!(
                "the header declares {columns}x{rows} samples but the file holds only {} bytes",
                bytes.len()
            ),
        ));
    }
    let (columns, rows) = (columns as u32, rows as u32);
    let mut heights = Vec::with_capacity(count as usize);
    for (index, line) in lines {
        let line_number = index + 1;
        for word in line.split_whitespace() {
            let row = heights.len() / columns as usize + 1;
            if heights.len() == count as usize {
                return Err(DemError::new(
                    name,
                    format!(
                        "line {line_number}: more than the {rows} rows of {columns} numbers the header declares"
                    ),
                ));
            }
            let value: f64 = word.parse().map_err(|_| {
                DemError::new(name, format!("line {line_number} (row {row}): `{word}` is not a number"))
            })?;
            let is_nodata =
                header.nodata.is_some_and(|nodata| value == nodata || value as f32 == nodata as f32);
            heights.push(if is_nodata || !value.is_finite() { f32::NAN } else { value as f32 });
        }
    }
    if heights.len() != count as usize {
        let full_rows = heights.len() / columns as usize;
        return Err(DemError::new(
            name,
            format!(
                "{} numbers for {rows} rows of {columns}: row {} is missing or short",
                heights.len(),
                full_rows + 1
            ),
        ));
    }
    let (x, x_centre) = header.x.unwrap_or((0.0, false));
    let (y, y_centre) = header.y.unwrap_or((0.0, false));
    if !(cell_x > 0.0 && cell_y > 0.0 && cell_x.is_finite() && cell_y.is_finite()) {
        return Err(DemError::new(name, format!("the cell size {cell_x} x {cell_y} is not positive")));
    }
    let south = if y_centre { y - cell_y / 2.0 } else { y };
    let west = if x_centre { x - cell_x / 2.0 } else { x };
    let north = south + cell_y * f64::from(rows);
    let east = west + cell_x * f64::from(columns);
    let geographic =
        cell_x < 0.01 && cell_y < 0.01 && west >= -180.0 && east <= 180.0 && south >= -90.0 && north <= 90.0;
    let spacing = if geographic {
        Spacing::Degrees { longitude: cell_x, latitude: cell_y, centre_latitude: (south + north) / 2.0 }
    } else {
        Spacing::Metres { x: cell_x, y: cell_y }
    };
    Ok(Elevation { columns, rows, heights, spacing })
}

#[derive(Debug, Default)]
struct Header {
    columns: Option<u64>,
    rows: Option<u64>,
    x: Option<(f64, bool)>,
    y: Option<(f64, bool)>,
    cell: Option<(f64, f64)>,
    nodata: Option<f64>,
}

fn whole(number: f64, key: &str, line: usize, name: &str) -> Result<u64, DemError> {
    if number >= 0.0 && number.fract() == 0.0 && number < 1e12 {
        Ok(number as u64)
    } else {
        Err(DemError::new(name, format!("line {line}: `{key}` must be a whole number, not {number}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIMIT: SizeLimit = SizeLimit { allow_downsampling: false };

    #[test]
    fn reads_a_projected_grid_with_nodata() {
        let text = "ncols 3\nnrows 2\nxllcorner 500000\nyllcorner 4000000\ncellsize 30\nNODATA_value -9999\n1 2 3\n4 -9999 6.5\n";
        let dem = read(text.as_bytes(), "a.asc", LIMIT).expect("valid");
        assert_eq!((dem.columns, dem.rows), (3, 2));
        assert_eq!(&dem.heights[..4], &[1.0, 2.0, 3.0, 4.0]);
        assert!(dem.heights[4].is_nan());
        assert_eq!(dem.heights[5], 6.5);
        assert_eq!(dem.spacing, Spacing::Metres { x: 30.0, y: 30.0 });
    }

    #[test]
    fn small_cells_within_the_globe_are_degrees() {
        let text = "NCOLS 2\nNROWS 2\nXLLCENTER -105.5\nYLLCENTER 40.0\nCELLSIZE 0.001\n1 2\n3 4\n";
        let dem = read(text.as_bytes(), "g.asc", LIMIT).expect("valid");
        let Spacing::Degrees { centre_latitude, .. } = dem.spacing else {
            panic!("degrees: {:?}", dem.spacing)
        };
        assert!((centre_latitude - 40.0005).abs() < 1e-9);
    }

    #[test]
    fn a_missing_row_and_a_non_number_are_named() {
        let short = "ncols 2\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3 4\n";
        let error = read(short.as_bytes(), "short.asc", LIMIT).expect_err("short").to_string();
        assert!(error.contains("short.asc") && error.contains("row 3 is missing"), "{error}");
        let bad = "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3 x4\n";
        let error = read(bad.as_bytes(), "bad.asc", LIMIT).expect_err("bad").to_string();
        assert_eq!(error, "bad.asc: line 7 (row 2): `x4` is not a number");
    }

    #[test]
    fn a_lying_header_is_refused_before_allocating() {
        let text = "ncols 8000\nnrows 8000\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n";
        let error = read(text.as_bytes(), "lie.asc", LIMIT).expect_err("lie").to_string();
        assert!(error.contains("declares 8000x8000 samples but the file holds only"), "{error}");
        let huge = "ncols 100000\nnrows 100000\ncellsize 1\n";
        let error = read(huge.as_bytes(), "huge.asc", LIMIT).expect_err("huge").to_string();
        assert!(error.contains("refused before decoding"), "{error}");
    }
}
