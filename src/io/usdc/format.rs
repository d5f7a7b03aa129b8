//! Constants of the crate format shared by the reader and the writer.

pub const MAGIC: &[u8; 8] = b"PXR-USDC";

/// The version coif writes (what usd-core writes by default): compressed structural sections
/// (0.4), compressed integer arrays (0.5), 64-bit array sizes (0.7).
pub const VERSION: (u8, u8, u8) = (0, 8, 0);

/// Identifier, version, TOC offset and eight reserved 64-bit words.
pub const BOOTSTRAP_SIZE: usize = 88;

/// Arrays shorter than this are never compressed.
pub const MIN_COMPRESSED_ARRAY: usize = 16;

/// The structural sections, in the order coif writes them.
pub const SECTIONS: [&str; 6] = ["TOKENS", "STRINGS", "FIELDS", "FIELDSETS", "PATHS", "SPECS"];

/// Value types (the numbering of USD's `crateDataTypes.h`), those coif writes or decodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Type {
    Bool = 1,
    Uchar = 2,
    Int = 3,
    Uint = 4,
    Int64 = 5,
    Uint64 = 6,
    Half = 7,
    Float = 8,
    Double = 9,
    String = 10,
    Token = 11,
    AssetPath = 12,
    Matrix2d = 13,
    Matrix3d = 14,
    Matrix4d = 15,
    Quatd = 16,
    Quatf = 17,
    Quath = 18,
    Vec2d = 19,
    Vec2f = 20,
    Vec2h = 21,
    Vec2i = 22,
    Vec3d = 23,
    Vec3f = 24,
    Vec3h = 25,
    Vec3i = 26,
    Vec4d = 27,
    Vec4f = 28,
    Vec4h = 29,
    Vec4i = 30,
    Dictionary = 31,
    TokenListOp = 32,
    StringListOp = 33,
    PathListOp = 34,
    ReferenceListOp = 35,
    TokenVector = 41,
    Specifier = 42,
    Variability = 44,
    VariantSelectionMap = 45,
    TimeSamples = 46,
    Payload = 47,
    DoubleVector = 48,
    LayerOffsetVector = 49,
    StringVector = 50,
    ValueBlock = 51,
    PayloadListOp = 55,
    TimeCode = 56,
}

impl Type {
    pub fn from_u8(value: u8) -> Option<Type> {
        use Type::*;
        const ALL: [Type; 47] = [
            Bool,
            Uchar,
            Int,
            Uint,
            Int64,
            Uint64,
            Half,
            Float,
            Double,
            String,
            Token,
            AssetPath,
            Matrix2d,
            Matrix3d,
            Matrix4d,
            Quatd,
            Quatf,
            Quath,
            Vec2d,
            Vec2f,
            Vec2h,
            Vec2i,
            Vec3d,
            Vec3f,
            Vec3h,
            Vec3i,
            Vec4d,
            Vec4f,
            Vec4h,
            Vec4i,
            Dictionary,
            TokenListOp,
            StringListOp,
            PathListOp,
            ReferenceListOp,
            TokenVector,
            Specifier,
            Variability,
            VariantSelectionMap,
            TimeSamples,
            Payload,
            DoubleVector,
            LayerOffsetVector,
            StringVector,
            ValueBlock,
            PayloadListOp,
            TimeCode,
        ];
        ALL.into_iter().find(|t| *t as u8 == value)
    }
}

/// Spec kinds (`SdfSpecType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpecType {
    Attribute = 1,
    Prim = 6,
    PseudoRoot = 7,
    Variant = 10,
}

/// `SdfSpecifier`: only `def` defines a prim on a flattened stage.
pub const SPECIFIER_DEF: u64 = 0;
pub const SPECIFIER_CLASS: u64 = 2;
/// `SdfVariability`.
pub const VARYING: u64 = 0;
pub const UNIFORM: u64 = 1;

/// Value representations: bit 63 array, 62 inline, 61 compressed, 48..56 the type.
pub mod rep {
    use super::Type;

    pub const ARRAY: u64 = 1 << 63;
    pub const INLINE: u64 = 1 << 62;
    pub const COMPRESSED: u64 = 1 << 61;
    pub const PAYLOAD: u64 = (1 << 48) - 1;

    pub fn inline(kind: Type, payload: u64) -> u64 {
        INLINE | (kind as u64) << 48 | (payload & PAYLOAD)
    }
    pub fn at(kind: Type, offset: u64) -> u64 {
        (kind as u64) << 48 | (offset & PAYLOAD)
    }
    pub fn array_at(kind: Type, offset: u64) -> u64 {
        ARRAY | at(kind, offset)
    }
    pub fn compressed(rep: u64) -> u64 {
        rep | COMPRESSED
    }
    pub fn type_byte(rep: u64) -> u8 {
        (rep >> 48) as u8
    }
    pub fn payload(rep: u64) -> u64 {
        rep & PAYLOAD
    }
    pub fn is_array(rep: u64) -> bool {
        rep & ARRAY != 0
    }
    pub fn is_inline(rep: u64) -> bool {
        rep & INLINE != 0
    }
    pub fn is_compressed(rep: u64) -> bool {
        rep & COMPRESSED != 0
    }
}
