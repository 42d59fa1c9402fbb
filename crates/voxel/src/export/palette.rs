//! A palette of at most 255 colours for VOX (index 0 is empty there): the colours
//! themselves when there are that few, else a median cut of the sRGB colours weighted by
//! how many voxels have each (boxes split along their widest channel at the weighted
//! median until there are 255), each box's weighted mean its entry, and each colour mapped
//! to the nearest entry.

use std::collections::HashMap;

/// The palette (at most `max` entries) and, per distinct colour, its entry.
pub fn quantize(colors: &[[u8; 4]], max: usize) -> (Vec<[u8; 4]>, HashMap<[u8; 4], u8>) {
    let mut counts: HashMap<[u8; 4], u64> = HashMap::new();
    for c in colors {
        *counts.entry(*c).or_default() += 1;
    }
    let mut distinct: Vec<([u8; 4], u64)> = counts.into_iter().collect();
    distinct.sort();
    if distinct.len() <= max {
        let map = distinct
            .iter()
            .enumerate()
            .map(|(i, (c, _))| (*c, i as u8))
            .collect();
        return (distinct.into_iter().map(|(c, _)| c).collect(), map);
    }
    let mut boxes = vec![distinct];
    while boxes.len() < max {
        // The box with the widest channel range among those that can split.
        let Some((bi, ch)) = boxes
            .iter()
            .enumerate()
            .filter(|(_, b)| b.len() > 1)
            .map(|(i, b)| {
                let (ch, range) = (0..4)
                    .map(|ch| {
                        let lo = b.iter().map(|(c, _)| c[ch]).min().unwrap_or(0);
                        let hi = b.iter().map(|(c, _)| c[ch]).max().unwrap_or(0);
                        (ch, hi - lo)
                    })
                    .max_by_key(|(_, r)| *r)
                    .unwrap_or((0, 0));
                (i, ch, range)
            })
            .max_by_key(|(_, _, r)| *r)
            .map(|(i, ch, _)| (i, ch))
        else {
            break;
        };
        let mut b = boxes.swap_remove(bi);
        b.sort_by_key(|(c, _)| c[ch]);
        let total: u64 = b.iter().map(|(_, n)| n).sum();
        let mut acc = 0;
        let mut at = b.len() / 2;
        for (i, (_, n)) in b.iter().enumerate() {
            acc += n;
            if acc * 2 >= total {
                at = (i + 1).clamp(1, b.len() - 1);
                break;
            }
        }
        let rest = b.split_off(at);
        boxes.push(b);
        boxes.push(rest);
    }
    let palette: Vec<[u8; 4]> = boxes
        .iter()
        .map(|b| {
            let total: u64 = b.iter().map(|(_, n)| n).sum::<u64>().max(1);
            std::array::from_fn(|ch| {
                let s: u64 = b.iter().map(|(c, n)| u64::from(c[ch]) * n).sum();
                ((s + total / 2) / total) as u8
            })
        })
        .collect();
    let map = boxes
        .iter()
        .flatten()
        .map(|(c, _)| (*c, nearest(&palette, *c)))
        .collect();
    (palette, map)
}

/// The index of the entry of `palette` nearest to `c` (squared distance over RGBA).
fn nearest(palette: &[[u8; 4]], c: [u8; 4]) -> u8 {
    let d = |p: &[u8; 4]| -> u32 {
        (0..4)
            .map(|i| (i32::from(p[i]) - i32::from(c[i])).pow(2) as u32)
            .sum()
    };
    palette
        .iter()
        .enumerate()
        .min_by_key(|(_, p)| d(p))
        .map_or(0, |(i, _)| i as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn few_colours_are_kept_and_many_are_cut_to_the_nearest() {
        let few = [[10, 20, 30, 255], [10, 20, 30, 255], [200, 0, 0, 255]];
        let (p, map) = quantize(&few, 255);
        assert_eq!(p.len(), 2);
        for c in few {
            assert_eq!(p[map[&c] as usize], c);
        }
        // 4096 distinct greys-and-reds into 255 entries: each colour lands within a
        // sixteenth of the range of its entry.
        let many: Vec<[u8; 4]> = (0..4096u32)
            .map(|i| [(i % 64 * 4) as u8, (i / 64 * 4) as u8, 7, 255])
            .collect();
        let (p, map) = quantize(&many, 255);
        assert_eq!(p.len(), 255);
        let worst = many
            .iter()
            .map(|c| {
                let q = p[map[c] as usize];
                (0..4)
                    .map(|i| (i32::from(q[i]) - i32::from(c[i])).abs())
                    .max()
                    .unwrap()
            })
            .max()
            .unwrap();
        assert!(worst <= 16, "{worst}");
    }
}
