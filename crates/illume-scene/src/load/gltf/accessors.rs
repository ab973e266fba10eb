//! Accessors: typed, checked reads of buffer views (component types, counts, byte
//! ranges, finite values).

use super::Ctx;
use crate::load::LoadError;
use ::gltf::json;
use json::validation::Checked;

/// Largest number of values (elements × components) of an accessor *without* a buffer
/// view (all zeros) accepted: guards memory against absurd counts. Accessors with data
/// are bounded by their buffer's size instead.
pub(super) const MAX_ZERO_ACCESSOR_VALUES: u64 = 1 << 26;

pub(super) fn component_size(c: json::accessor::ComponentType) -> usize {
    use json::accessor::ComponentType as C;
    match c {
        C::I8 | C::U8 => 1,
        C::I16 | C::U16 => 2,
        C::U32 | C::F32 => 4,
    }
}

pub(super) fn components(t: json::accessor::Type) -> usize {
    use json::accessor::Type as T;
    match t {
        T::Scalar => 1,
        T::Vec2 => 2,
        T::Vec3 => 3,
        T::Vec4 | T::Mat2 => 4,
        T::Mat3 => 9,
        T::Mat4 => 16,
    }
}

impl Ctx<'_> {
    /// The bytes of buffer view `index`, bounds-checked against its buffer.
    pub(super) fn view_bytes(&self, index: usize) -> Result<&[u8], LoadError> {
        let place = format!("bufferView {index}");
        let view = self
            .root
            .buffer_views
            .get(index)
            .ok_or_else(|| self.malformed(&place, "does not exist"))?;
        let b = view.buffer.value();
        let buffer = self
            .buffers
            .get(b)
            .ok_or_else(|| self.malformed(&place, format!("buffer {b} does not exist")))?;
        let start = view.byte_offset.map(|o| o.0).unwrap_or(0);
        let end = start.saturating_add(view.byte_length.0);
        if end > buffer.len() as u64 {
            return Err(self.malformed(
                place,
                format!(
                    "bytes {start}..{end} exceed buffer {b} ({} bytes)",
                    buffer.len()
                ),
            ));
        }
        Ok(&buffer[start as usize..end as usize])
    }

    /// Reads accessor `index` as `f64`s (`count × components`, row by row; normalized
    /// integers mapped to [0, 1] or [−1, 1]) and returns them with the component count.
    /// `what` names the use for messages. Non-finite values are an error.
    pub(super) fn read_accessor(
        &self,
        index: usize,
        what: &str,
    ) -> Result<(Vec<f64>, usize), LoadError> {
        let place = format!("accessor {index} ({what})");
        let acc = self
            .root
            .accessors
            .get(index)
            .ok_or_else(|| self.malformed(&place, "does not exist"))?;
        let (Checked::Valid(ty), Checked::Valid(json::accessor::GenericComponentType(ct))) =
            (&acc.type_, &acc.component_type)
        else {
            return Err(self.malformed(place, "invalid type or componentType"));
        };
        if acc.sparse.is_some() {
            return Err(LoadError::unsupported(self.path, place, "sparse accessors"));
        }
        let n_comp = components(*ty);
        let count = acc.count.0;
        if count == 0 {
            return Err(self.malformed(place, "count 0 (glTF requires at least 1)"));
        }
        let Some(view_index) = acc.buffer_view.map(|v| v.value()) else {
            if count.saturating_mul(n_comp as u64) > MAX_ZERO_ACCESSOR_VALUES {
                return Err(self.malformed(place, format!("count {count} is too large")));
            }
            // glTF: an accessor without a buffer view is all zeros.
            return Ok((vec![0.0; count as usize * n_comp], n_comp));
        };
        let count = usize::try_from(count)
            .map_err(|_| self.malformed(&place, format!("count {count} is too large")))?;
        let bytes = self.view_bytes(view_index)?;
        let csize = component_size(*ct);
        let elem = (csize * n_comp) as u64;
        let stride = self
            .root
            .buffer_views
            .get(view_index)
            .and_then(|v| v.byte_stride)
            .map(|s| s.0 as u64)
            .unwrap_or(elem);
        let offset = acc.byte_offset.map(|o| o.0).unwrap_or(0);
        if count > 0 {
            let end = (count as u64 - 1)
                .checked_mul(stride)
                .and_then(|x| x.checked_add(offset))
                .and_then(|x| x.checked_add(elem));
            if end.is_none_or(|e| e > bytes.len() as u64) {
                return Err(self.malformed(
                    place,
                    format!("{count} elements of {elem} bytes (stride {stride}) from offset {offset} exceed bufferView {view_index} ({} bytes)", bytes.len()),
                ));
            }
        }
        use json::accessor::ComponentType as C;
        let normalized = acc.normalized;
        let mut out = Vec::with_capacity(count * n_comp);
        for i in 0..count {
            let base = offset as usize + i * stride as usize;
            for c in 0..n_comp {
                let at = base + c * csize;
                let b = bytes
                    .get(at..at + csize)
                    .ok_or_else(|| self.malformed(&place, format!("element {i} out of bounds")))?;
                let x = match ct {
                    C::I8 => {
                        let v = b[0] as i8 as f64;
                        if normalized { (v / 127.0).max(-1.0) } else { v }
                    }
                    C::U8 => {
                        let v = b[0] as f64;
                        if normalized { v / 255.0 } else { v }
                    }
                    C::I16 => {
                        let v = i16::from_le_bytes([b[0], b[1]]) as f64;
                        if normalized {
                            (v / 32767.0).max(-1.0)
                        } else {
                            v
                        }
                    }
                    C::U16 => {
                        let v = u16::from_le_bytes([b[0], b[1]]) as f64;
                        if normalized { v / 65535.0 } else { v }
                    }
                    C::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    C::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                };
                if !x.is_finite() {
                    return Err(self.malformed(
                        place,
                        format!("element {i} component {c} is not finite ({x})"),
                    ));
                }
                out.push(x);
            }
        }
        Ok((out, n_comp))
    }

    /// Checks that accessor `index` (used as `what`) has one of the component types glTF
    /// allows for that use (`allowed`, named `names` in the message). A missing accessor
    /// is left to [`Ctx::read_accessor`] to report.
    pub(super) fn check_component_type(
        &self,
        index: usize,
        what: &str,
        allowed: &[json::accessor::ComponentType],
        names: &str,
    ) -> Result<(), LoadError> {
        if let Some(acc) = self.root.accessors.get(index)
            && let Checked::Valid(json::accessor::GenericComponentType(ct)) = acc.component_type
            && !allowed.contains(&ct)
        {
            return Err(self.malformed(
                format!("accessor {index} ({what})"),
                format!("componentType {ct:?} is not allowed here (only {names})"),
            ));
        }
        Ok(())
    }

    /// Reads an accessor that must have `n` components per element, as `f32` arrays.
    pub(super) fn read_vecs<const N: usize>(
        &self,
        index: usize,
        what: &str,
    ) -> Result<Vec<[f32; N]>, LoadError> {
        let (v, n) = self.read_accessor(index, what)?;
        if n != N {
            return Err(self.malformed(
                format!("accessor {index} ({what})"),
                format!("has {n} components per element, expected {N}"),
            ));
        }
        Ok(v.chunks_exact(N)
            .map(|c| std::array::from_fn(|k| c[k] as f32))
            .collect())
    }
}
