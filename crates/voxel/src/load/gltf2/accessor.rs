//! Accessors: buffer views, dense and sparse accessor storage, component decoding.

use std::rc::Rc;

use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;

use super::Builder;
use super::values::Values;
use crate::load::error::LoadError;

impl Builder<'_> {
    /// The bytes of a buffer view, range-checked.
    pub(super) fn view_bytes(&self, view_index: usize) -> Result<&[u8], LoadError> {
        let view = self
            .root
            .buffer_views
            .get(view_index)
            .ok_or_else(|| self.err(format!("buffer view {view_index} does not exist")))?;
        let buffer = self
            .buffers
            .get(view.buffer.value())
            .ok_or_else(|| self.err(format!("buffer {} does not exist", view.buffer.value())))?;
        let start = view.byte_offset.map_or(0, |o| o.0);
        let end = start.checked_add(view.byte_length.0);
        match end.filter(|&e| e <= buffer.len() as u64) {
            Some(end) => Ok(&buffer[start as usize..end as usize]),
            None => Err(self.err(format!(
                "buffer view {view_index} (bytes {start}..+{}) lies outside buffer {} ({} bytes)",
                view.byte_length.0,
                view.buffer.value(),
                buffer.len()
            ))),
        }
    }

    /// An accessor's values, decoded once however many primitives or instances use it.
    pub(super) fn accessor(
        &mut self,
        index: usize,
        what: &str,
        types: &[Type],
    ) -> Result<Rc<Values>, LoadError> {
        if let Some(v) = self.accessor_cache.get(&index) {
            // The same accessor may serve several semantics: re-check the type for this one.
            let ok = self
                .root
                .accessors
                .get(index)
                .is_some_and(|a| matches!(a.type_, Checked::Valid(t) if types.contains(&t)));
            if ok {
                return Ok(Rc::clone(v));
            }
        }
        let values = Rc::new(self.read_accessor(index, what, types)?);
        self.accessor_cache.insert(index, Rc::clone(&values));
        Ok(values)
    }

    /// Reads an accessor (dense and/or sparse) after checking every byte range it covers.
    fn read_accessor(&self, index: usize, what: &str, types: &[Type]) -> Result<Values, LoadError> {
        let acc = self
            .root
            .accessors
            .get(index)
            .ok_or_else(|| self.err(format!("{what}: accessor {index} does not exist")))?;
        let err = |m: String| self.err(format!("{what} (accessor {index}): {m}"));
        let component = match &acc.component_type {
            Checked::Valid(c) => c.0,
            Checked::Invalid => return Err(err("invalid component type".into())),
        };
        let ty = match acc.type_ {
            Checked::Valid(t) if types.contains(&t) => t,
            Checked::Valid(t) => {
                return Err(err(format!(
                    "type {t:?} is not allowed here (expected {types:?})"
                )));
            }
            Checked::Invalid => return Err(err("invalid accessor type".into())),
        };
        let components = ty.multiplicity();
        let count = acc.count.0;
        let elem = component.size() * components;
        let normalized = acc.normalized;
        let mut data: Vec<f64>;
        match acc.buffer_view {
            Some(view_index) => {
                let bytes = self.view_bytes(view_index.value())?;
                let stride = self
                    .root
                    .buffer_views
                    .get(view_index.value())
                    .and_then(|v| v.byte_stride)
                    .map_or(elem, |s| s.0);
                if stride < elem {
                    return Err(err(format!(
                        "byte stride {stride} is smaller than the element size {elem}"
                    )));
                }
                let offset = acc.byte_offset.map_or(0, |o| o.0);
                let span = if count == 0 {
                    Some(0)
                } else {
                    (count - 1)
                        .checked_mul(stride as u64)
                        .and_then(|s| s.checked_add(elem as u64))
                        .and_then(|s| s.checked_add(offset))
                };
                if span.is_none_or(|s| s > bytes.len() as u64) {
                    return Err(err(format!(
                        "{count} elements of {elem} bytes (stride {stride}, offset {offset}) overrun the {}-byte buffer view",
                        bytes.len()
                    )));
                }
                // `count` is now bounded by the buffer's size, so these allocations are too.
                let (count, offset) = (count as usize, offset as usize);
                data = Vec::with_capacity(count * components);
                for i in 0..count {
                    let at = offset + i * stride;
                    for c in 0..components {
                        data.push(decode_component(
                            bytes,
                            at + c * component.size(),
                            component,
                            normalized,
                        ));
                    }
                }
            }
            None => {
                if count > self.zero_fill_limit {
                    return Err(LoadError::too_large(
                        self.path,
                        "zero-filled accessor elements",
                        count,
                        self.zero_fill_limit,
                    ));
                }
                data = vec![0.0; count as usize * components];
            }
        }
        if let Some(sparse) = &acc.sparse {
            let n = sparse.count.0;
            if n > count {
                return Err(err(format!("{n} sparse entries for {count} elements")));
            }
            let index_type = match &sparse.indices.component_type {
                Checked::Valid(c) => c.0,
                Checked::Invalid => return Err(err("invalid sparse index type".into())),
            };
            let idx_bytes = self.view_bytes(sparse.indices.buffer_view.value())?;
            let idx_off = sparse.indices.byte_offset.0;
            let val_bytes = self.view_bytes(sparse.values.buffer_view.value())?;
            let val_off = sparse.values.byte_offset.0;
            let fits = |off: u64, size: usize, len: usize| {
                n.checked_mul(size as u64)
                    .and_then(|s| s.checked_add(off))
                    .is_some_and(|end| end <= len as u64)
            };
            if !fits(idx_off, index_type.size(), idx_bytes.len())
                || !fits(val_off, elem, val_bytes.len())
            {
                return Err(err(
                    "sparse indices or values overrun their buffer views".into()
                ));
            }
            for k in 0..n as usize {
                let target = decode_component(
                    idx_bytes,
                    idx_off as usize + k * index_type.size(),
                    index_type,
                    false,
                );
                if target < 0.0 || target >= count as f64 {
                    return Err(err(format!("sparse index {target} is out of range")));
                }
                for c in 0..components {
                    let v = decode_component(
                        val_bytes,
                        val_off as usize + k * elem + c * component.size(),
                        component,
                        normalized,
                    );
                    if let Some(slot) = data.get_mut(target as usize * components + c) {
                        *slot = v;
                    }
                }
            }
        }
        Ok(Values {
            data,
            components,
            count: count as usize,
        })
    }
}

/// Decodes one component (little-endian) at byte `at`; out-of-range reads give 0 (they
/// cannot happen: every range is checked before decoding).
fn decode_component(bytes: &[u8], at: usize, component: ComponentType, normalized: bool) -> f64 {
    fn get<const N: usize>(bytes: &[u8], at: usize) -> [u8; N] {
        let mut a = [0u8; N];
        if let Some(s) = at.checked_add(N).and_then(|end| bytes.get(at..end)) {
            a.copy_from_slice(s);
        }
        a
    }
    match component {
        ComponentType::F32 => f32::from_le_bytes(get(bytes, at)) as f64,
        ComponentType::U8 => {
            let v = get::<1>(bytes, at)[0] as f64;
            if normalized { v / 255.0 } else { v }
        }
        ComponentType::I8 => {
            let v = get::<1>(bytes, at)[0] as i8 as f64;
            if normalized { (v / 127.0).max(-1.0) } else { v }
        }
        ComponentType::U16 => {
            let v = u16::from_le_bytes(get(bytes, at)) as f64;
            if normalized { v / 65535.0 } else { v }
        }
        ComponentType::I16 => {
            let v = i16::from_le_bytes(get(bytes, at)) as f64;
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        ComponentType::U32 => {
            let v = u32::from_le_bytes(get(bytes, at)) as f64;
            if normalized { v / u32::MAX as f64 } else { v }
        }
    }
}
