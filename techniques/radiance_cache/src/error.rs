//! Why temporal radiance caching could not start or could not take an input.

/// Why temporal radiance caching could not start or could not take an input.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RadianceCacheError {
    /// A setting is out of range or not a number.
    #[error("radiance_cache.{field}: {reason}")]
    InvalidSetting {
        /// The field.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// A hemispherical-harmonics order outside what [`crate::hsh`] supports.
    #[error("radiance_cache: HSH order {order} is not in 1..={max}")]
    HshOrder {
        /// The order asked for.
        order: usize,
        /// The largest order supported ([`crate::hsh::MAX_ORDER`]).
        max: usize,
    },
    /// A record cannot be computed at this point: the position or normal is not finite,
    /// or the normal has no length.
    #[error("radiance_cache: no record at {position} with normal {normal}: {reason}")]
    BadRecordPoint {
        /// The point asked for.
        position: illume_core::Vec3,
        /// The normal asked for.
        normal: illume_core::Vec3,
        /// What is wrong.
        reason: &'static str,
    },
    /// An octree entry that is not finite (centre or radius), or a negative radius.
    #[error(
        "radiance_cache: record {id}: sphere of influence at {center} with radius {radius} m is not finite and non-negative"
    )]
    BadSphere {
        /// The record.
        id: u32,
        /// Its centre.
        center: illume_core::Vec3,
        /// Its radius.
        radius: f32,
    },
    /// Interpolated temporal gradients (Eq. 21–23) need a replacing record strictly
    /// after the replaced one.
    #[error(
        "radiance_cache: temporal interpolation from frame {from} to frame {to} needs to > from"
    )]
    TemporalOrder {
        /// Frame of the replaced record k.
        from: u32,
        /// Frame of the replacing record l.
        to: u32,
    },
}
