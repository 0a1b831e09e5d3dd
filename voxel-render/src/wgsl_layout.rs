//! Test support: compares a Rust `#[repr(C)]` struct with the WGSL struct of the same role,
//! as naga (the shader compiler wgpu uses) lays it out, so that the two cannot drift apart.

/// A Rust field: name, byte offset, byte size.
pub(crate) type Field = (&'static str, usize, usize);

/// `(name, offset, size)` of a field of a Rust struct.
macro_rules! field {
    ($ty:ty, $name:ident) => {{
        fn size<T>(_: impl Fn(&$ty) -> &T) -> usize {
            std::mem::size_of::<T>()
        }
        (
            stringify!($name),
            std::mem::offset_of!($ty, $name),
            size(|s: &$ty| &s.$name),
        )
    }};
}
pub(crate) use field;

/// Parses WGSL source (panics with naga's message on a syntax error).
pub(crate) fn parse(source: &str) -> naga::Module {
    naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("WGSL does not parse: {}", e.emit_to_string(source)))
}

/// Asserts that WGSL struct `name` of `module` has exactly `fields` (same names in the same
/// order, same offsets and sizes) and the size of `T`.
pub(crate) fn assert_layout<T>(module: &naga::Module, name: &str, fields: &[Field]) {
    let (members, span) = module
        .types
        .iter()
        .find_map(|(_, ty)| match &ty.inner {
            naga::TypeInner::Struct { members, span } if ty.name.as_deref() == Some(name) => {
                Some((members, *span))
            }
            _ => None,
        })
        .unwrap_or_else(|| panic!("no WGSL struct {name}"));
    let ctx = module.to_ctx();
    let wgsl: Vec<(String, usize, usize)> = members
        .iter()
        .map(|m| {
            (
                m.name.clone().unwrap_or_default(),
                m.offset as usize,
                module.types[m.ty].inner.size(ctx) as usize,
            )
        })
        .collect();
    let rust: Vec<(String, usize, usize)> = fields
        .iter()
        .map(|(n, o, s)| ((*n).to_owned(), *o, *s))
        .collect();
    assert_eq!(
        wgsl, rust,
        "struct {name}: WGSL (left) and Rust (right) differ"
    );
    assert_eq!(
        span as usize,
        std::mem::size_of::<T>(),
        "struct {name}: WGSL size (left) and Rust size (right) differ"
    );
}
