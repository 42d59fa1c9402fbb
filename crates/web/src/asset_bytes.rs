//! A prepared asset as one byte buffer, for the hop from the page's voxelizing worker to
//! the page (a `postMessage` transfer). Both ends are this build of this crate, so the
//! layout has no version; [`decode`] still checks every length against the bytes, so a
//! short or damaged buffer is an error, never a panic or an oversized allocation.
//!
//! Layout (little-endian): `levels: u32`, the object space (`center: 3 × f64`,
//! `scale: f64`), then per level `level, depth: u32`, and four length-prefixed arrays
//! (`u32` count, then the items): voxels (16 bytes), lookup nodes (`u32`), proxy positions
//! (`3 × f32`), proxy triangles (`3 × u32`).

use bytemuck::Pod;
use glam::DVec3;
use ssbvb_voxel::asset::{LodLevel, PackedVoxel, PointCloud, ProxyMesh, VoxelAsset};
use ssbvb_voxel::lookup::SparseLookup;
use ssbvb_voxel::model::ObjectSpace;

use crate::WebError;

/// `asset` as bytes.
pub fn encode(asset: &VoxelAsset) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(&(asset.lods.len() as u32).to_le_bytes());
    let s = &asset.object_space;
    for v in [s.center.x, s.center.y, s.center.z, s.scale] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for lod in &asset.lods {
        out.extend_from_slice(&lod.level.to_le_bytes());
        out.extend_from_slice(&lod.lookup.depth.to_le_bytes());
        array(&mut out, &lod.point_cloud.voxels);
        array(&mut out, &lod.lookup.nodes);
        array(&mut out, &lod.proxy.positions);
        array(&mut out, &lod.proxy.triangles);
    }
    out
}

fn array<T: Pod>(out: &mut Vec<u8>, items: &[T]) {
    out.extend_from_slice(&(items.len() as u32).to_le_bytes());
    out.extend_from_slice(bytemuck::cast_slice(items));
}

/// Reads what [`encode`] wrote.
pub fn decode(bytes: &[u8]) -> Result<VoxelAsset, WebError> {
    let mut r = Reader { bytes, at: 0 };
    let levels = r.u32()?;
    if levels == 0 || levels > 32 {
        return Err(damaged(format!("{levels} levels")));
    }
    let mut f = [0.0f64; 4];
    for v in &mut f {
        *v = f64::from_le_bytes(r.take(8)?.try_into().expect("8 bytes"));
    }
    let object_space = ObjectSpace {
        center: DVec3::new(f[0], f[1], f[2]),
        scale: f[3],
    };
    let mut lods = Vec::with_capacity(levels as usize);
    for _ in 0..levels {
        let level = r.u32()?;
        let depth = r.u32()?;
        let voxels: Vec<PackedVoxel> = r.array()?;
        let nodes: Vec<u32> = r.array()?;
        let positions: Vec<[f32; 3]> = r.array()?;
        let triangles: Vec<[u32; 3]> = r.array()?;
        lods.push(LodLevel {
            level,
            point_cloud: PointCloud { voxels },
            lookup: SparseLookup {
                level,
                depth,
                nodes,
            },
            proxy: ProxyMesh {
                positions,
                triangles,
            },
        });
    }
    if r.at != bytes.len() {
        return Err(damaged(format!("{} bytes left over", bytes.len() - r.at)));
    }
    Ok(VoxelAsset { object_space, lods })
}

fn damaged(what: String) -> WebError {
    WebError::Model {
        name: "the prepared asset".into(),
        message: format!("damaged on its way from the worker: {what}"),
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], WebError> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or_else(|| damaged(format!("{n} bytes wanted at {}", self.at)))?;
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }

    fn u32(&mut self) -> Result<u32, WebError> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }

    fn array<T: Pod>(&mut self) -> Result<Vec<T>, WebError> {
        let n = self.u32()? as usize;
        let size = std::mem::size_of::<T>();
        let len = n
            .checked_mul(size)
            .ok_or_else(|| damaged(format!("{n} items")))?;
        Ok(bytemuck::pod_collect_to_vec(self.take(len)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_asset_comes_back_whole_and_damage_is_an_error() {
        let tri = b"v -1 -1 -1\nv 1 -1 0\nv 0 1 1\nf 1 2 3\n";
        let asset = crate::scene_build::prepare_model(tri, "t.obj", 5)
            .unwrap()
            .0;
        let bytes = encode(&asset);
        assert!(decode(&bytes).unwrap() == asset);
        for cut in [0, 3, 20, bytes.len() / 2, bytes.len() - 1] {
            let e = decode(&bytes[..cut]).unwrap_err().to_string();
            assert!(
                e.contains("damaged on its way from the worker"),
                "{cut}: {e}"
            );
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(decode(&longer).is_err());
        // A count far beyond the bytes asks for nothing before it is refused.
        let mut huge = bytes;
        huge[44..48].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decode(&huge).is_err());
    }
}
