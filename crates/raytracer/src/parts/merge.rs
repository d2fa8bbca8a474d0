//! Merging part files into the full image.

use std::collections::BTreeMap;
use std::path::PathBuf;

use super::{Part, PartError, PartHeader, Split};
use crate::base::image_io::Image;
use crate::base::sampler::ExactSum;

/// Assembles part files into the full image: every tile of every pass must be there once, and all
/// must come from the same scene and settings. Parts are named by their paths in the errors.
pub fn merge(parts: &[(PathBuf, Part)]) -> Result<Image, PartError> {
    let Some((first_path, first)) = parts.first() else {
        return Err(PartError::Mismatch("no part files to merge".into()));
    };
    let f = &first.header;
    // Everything that must agree, with how to say it.
    type Key = fn(&PartHeader) -> String;
    let checks: [(&str, Key); 5] = [
        ("image size", |h| format!("{}x{}", h.width, h.height)),
        ("scene (its text, textures or meshes)", |h| h.scene.clone()),
        ("settings", |h| h.settings.clone()),
        ("number of tiles", |h| h.tile.count.to_string()),
        ("number of passes", |h| h.pass.count.to_string()),
    ];
    for (what, key) in checks {
        let want = key(f);
        if let Some((path, p)) = parts.iter().find(|(_, p)| key(&p.header) != want) {
            return Err(PartError::Mismatch(format!(
                "`{}` and `{}` are parts of different renders: their {what} differ ({} against {})",
                first_path.display(),
                path.display(),
                want,
                key(&p.header)
            )));
        }
    }
    let mut grid: BTreeMap<(u32, u32), &PathBuf> = BTreeMap::new();
    for (path, p) in parts {
        if let Some(other) = grid.insert((p.header.tile.index, p.header.pass.index), path) {
            return Err(PartError::Mismatch(format!(
                "`{}` and `{}` are the same part (tile {}, pass {}): merge each part once",
                other.display(),
                path.display(),
                p.header.tile,
                p.header.pass
            )));
        }
    }
    let missing: Vec<String> = (0..f.tile.count)
        .flat_map(|t| (0..f.pass.count).map(move |p| (t, p)))
        .filter(|key| !grid.contains_key(key))
        .map(|(t, p)| {
            describe(Split { index: t, count: f.tile.count }, Split { index: p, count: f.pass.count })
        })
        .collect();
    if !missing.is_empty() {
        let shown = missing.iter().take(20).cloned().collect::<Vec<_>>().join(", ");
        let more =
            if missing.len() > 20 { format!(" and {} more", missing.len() - 20) } else { String::new() };
        return Err(PartError::Mismatch(format!(
            "{} of {} parts are missing: {shown}{more}",
            missing.len(),
            f.tile.count as u64 * f.pass.count as u64
        )));
    }

    let w = f.width as usize;
    let mut pixels = vec![[0f32; 3]; w * f.height as usize];
    let by_key: BTreeMap<(u32, u32), &Part> =
        parts.iter().map(|(_, p)| ((p.header.tile.index, p.header.pass.index), p)).collect();
    for tile in 0..f.tile.count {
        let passes: Vec<&Part> = (0..f.pass.count).map(|p| by_key[&(tile, p)]).collect();
        for (b, block) in passes[0].blocks.iter().enumerate() {
            let out = &mut pixels[block.rows.start as usize * w..block.rows.end as usize * w];
            if f.pass.count == 1 {
                out.copy_from_slice(&block.pixels);
                continue;
            }
            // Passes: their exact sums added, divided by all their estimates.
            let count: u64 = passes.iter().map(|p| p.header.samples).sum();
            let mut total = vec![ExactSum::default(); out.len()];
            for p in &passes {
                let sums = p.blocks[b].sums.as_ref().expect("a pass part holds sums");
                total.iter_mut().zip(sums).for_each(|(t, s)| t.merge(s));
            }
            for (o, t) in out.iter_mut().zip(&total) {
                *o = t.mean(count).as_vec3().to_array();
            }
        }
    }
    Ok(Image::new(f.width, f.height, pixels))
}

/// `tile 2/8, pass 1/4`, leaving out a split into one.
fn describe(tile: Split, pass: Split) -> String {
    match (tile.count > 1, pass.count > 1) {
        (true, true) => format!("tile {tile} of pass {pass}"),
        (false, true) => format!("pass {pass}"),
        _ => format!("tile {tile}"),
    }
}
