//! A vertex reference of an OBJ element (`l`, `p`: `v`, `v/vt` or `v/vt/vn`, 1-based), read
//! once for every extra element flatcut writes into a piece's OBJ (dart lines, notches).

/// The 0-based vertex of the OBJ reference `token` in a file of `count` vertices, or what is
/// wrong with it.
pub(crate) fn obj_vertex(token: &str, count: usize) -> Result<u32, String> {
    let v: usize = token
        .split('/')
        .next()
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| format!("'{token}' is not a vertex index"))?;
    if v == 0 || v > count {
        return Err(format!(
            "vertex index {v} is out of range (the file has {count} vertices)"
        ));
    }
    Ok(v as u32 - 1)
}
