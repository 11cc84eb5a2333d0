//! The PLY scalar type names and the column each type decodes into.

use crate::mesh::{AttributeData, ScalarType};

pub(super) fn parse_type(name: &[u8]) -> Option<ScalarType> {
    Some(match name {
        b"char" | b"int8" => ScalarType::I8,
        b"uchar" | b"uint8" => ScalarType::U8,
        b"short" | b"int16" => ScalarType::I16,
        b"ushort" | b"uint16" => ScalarType::U16,
        b"int" | b"int32" => ScalarType::I32,
        b"uint" | b"uint32" => ScalarType::U32,
        b"float" | b"float32" => ScalarType::F32,
        b"double" | b"float64" => ScalarType::F64,
        _ => return None,
    })
}

pub(super) fn type_name(t: ScalarType) -> &'static str {
    match t {
        ScalarType::I8 => "char",
        ScalarType::U8 => "uchar",
        ScalarType::I16 => "short",
        ScalarType::U16 => "ushort",
        ScalarType::I32 => "int",
        ScalarType::U32 => "uint",
        ScalarType::F32 => "float",
        ScalarType::F64 => "double",
    }
}

pub(super) fn is_int(t: ScalarType) -> bool {
    !matches!(t, ScalarType::F32 | ScalarType::F64)
}

pub(super) fn empty_col(t: ScalarType, cap: usize) -> AttributeData {
    match t {
        ScalarType::I8 => AttributeData::I8(Vec::with_capacity(cap)),
        ScalarType::U8 => AttributeData::U8(Vec::with_capacity(cap)),
        ScalarType::I16 => AttributeData::I16(Vec::with_capacity(cap)),
        ScalarType::U16 => AttributeData::U16(Vec::with_capacity(cap)),
        ScalarType::I32 => AttributeData::I32(Vec::with_capacity(cap)),
        ScalarType::U32 => AttributeData::U32(Vec::with_capacity(cap)),
        ScalarType::F32 => AttributeData::F32(Vec::with_capacity(cap)),
        ScalarType::F64 => AttributeData::F64(Vec::with_capacity(cap)),
    }
}
