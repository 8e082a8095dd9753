//! Where the bodies of an assembly sit: the placements that `MAPPED_ITEM`s and context-dependent
//! shape representations (`CONTEXT_DEPENDENT_SHAPE_REPRESENTATION` with a
//! `REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION` and its `ITEM_DEFINED_TRANSFORMATION`) give
//! them, composed from the assembly's root down to every body, one placement per instance.
//!
//! Representations linked without a transformation (`SHAPE_REPRESENTATION_RELATIONSHIP`: a part's
//! shape representation and the B-rep representation that holds its solid) share one coordinate
//! space. A transformation links a component's space (the child) into its assembly's (the
//! parent): which side is the child is read from the `NEXT_ASSEMBLY_USAGE_OCCURRENCE` the
//! context-dependent representation names (writers order the relationship either way), else
//! `rep_1` is taken as the child as the CAx-IF recommended practices say. The child's axis
//! placement is carried onto the parent's: `T = P_parent · P_child⁻¹`; a `MAPPED_ITEM` carries
//! its representation map's origin onto its target the same way.

use std::collections::BTreeMap;

use crate::StepError;
use crate::attrs::Attrs;
use crate::file::{StepFile, Value};
use crate::placement::Placement;
use crate::reader::Reader;

/// Most instances of one body (a cycle guard and a bound on the work).
pub const MAX_INSTANCES: usize = 100_000;
/// Deepest nesting of assemblies followed.
const MAX_DEPTH: usize = 64;

/// The representations a file's shape representations hold, with their items.
const REPRESENTATIONS: [&str; 5] = [
    "ADVANCED_BREP_SHAPE_REPRESENTATION",
    "MANIFOLD_SURFACE_SHAPE_REPRESENTATION",
    "SHAPE_REPRESENTATION",
    "FACETED_BREP_SHAPE_REPRESENTATION",
    "GEOMETRICALLY_BOUNDED_SURFACE_SHAPE_REPRESENTATION",
];

/// A link from a child space into a parent space.
struct Link {
    child: u64,
    parent: u64,
    /// Child's frame and parent's frame (instance numbers of their axis placements), and the
    /// representations they are read in (for units).
    child_frame: (u64, u64),
    parent_frame: (u64, u64),
}

/// Union–find over representation ids: the coordinate spaces.
struct Spaces(BTreeMap<u64, u64>);

impl Spaces {
    fn find(&mut self, x: u64) -> u64 {
        let mut r = x;
        while let Some(&p) = self.0.get(&r) {
            if p == r {
                break;
            }
            r = p;
        }
        self.0.insert(x, r);
        r
    }
    fn join(&mut self, a: u64, b: u64) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.0.insert(ra.max(rb), ra.min(rb));
        }
    }
}

/// For every item of a representation, that representation (the first found).
fn items_of(file: &StepFile, r: &mut Reader) -> Result<BTreeMap<u64, u64>, StepError> {
    let mut out = BTreeMap::new();
    for t in REPRESENTATIONS {
        for rep in file.ids_of_type(t).collect::<Vec<_>>() {
            let items = r.visit(rep, rep, |_, inst| {
                Attrs::of(inst, &inst.parts[0]).refs(1, "items")
            })?;
            for i in items {
                out.entry(i).or_insert(rep);
            }
        }
    }
    Ok(out)
}

/// The shape representation of each product definition (`SHAPE_DEFINITION_REPRESENTATION` →
/// `PRODUCT_DEFINITION_SHAPE` → `PRODUCT_DEFINITION`).
fn rep_of_product_definition(
    file: &StepFile,
    r: &mut Reader,
) -> Result<BTreeMap<u64, u64>, StepError> {
    let mut out = BTreeMap::new();
    for sdr in file
        .ids_of_type("SHAPE_DEFINITION_REPRESENTATION")
        .collect::<Vec<_>>()
    {
        let (pds, rep) = r.visit(sdr, sdr, |_, inst| {
            let a = Attrs::of(inst, &inst.parts[0]);
            Ok((
                a.reference(0, "definition")?,
                a.reference(1, "used_representation")?,
            ))
        })?;
        let pd = r.visit(pds, sdr, |_, inst| {
            Attrs::of(inst, &inst.parts[0]).reference(2, "definition")
        });
        if let Ok(pd) = pd {
            out.entry(pd).or_insert(rep);
        }
    }
    Ok(out)
}

/// The links with a transformation, from context-dependent representations and mapped items.
fn links(
    file: &StepFile,
    r: &mut Reader,
    items: &BTreeMap<u64, u64>,
    spaces: &mut Spaces,
) -> Result<Vec<Link>, StepError> {
    let pd_rep = rep_of_product_definition(file, r)?;
    // The child product definition of each relationship a CDSR names.
    let mut child_pd: BTreeMap<u64, u64> = BTreeMap::new();
    for cdsr in file
        .ids_of_type("CONTEXT_DEPENDENT_SHAPE_REPRESENTATION")
        .collect::<Vec<_>>()
    {
        let (rr, pds) = r.visit(cdsr, cdsr, |_, inst| {
            let a = Attrs::of(inst, &inst.parts[0]);
            Ok((
                a.reference(0, "representation_relation")?,
                a.reference(1, "represented_product_relation")?,
            ))
        })?;
        let nauo = r.visit(pds, cdsr, |_, inst| {
            Attrs::of(inst, &inst.parts[0]).reference(2, "definition")
        })?;
        let child = r.visit(nauo, pds, |_, inst| {
            Attrs::of(inst, &inst.parts[0]).reference(4, "related_product_definition")
        });
        if let Ok(c) = child {
            child_pd.insert(rr, c);
        }
    }
    // Complex relationships: those without a transformation join spaces, the others link.
    let mut with_t: Vec<(u64, u64, u64, u64, u64)> = Vec::new();
    for id in file.complex_ids().collect::<Vec<_>>() {
        let rel = r.visit(id, id, |r, inst| {
            let Some(rr) = inst.part("REPRESENTATION_RELATIONSHIP") else {
                return Ok(None);
            };
            let a = Attrs::of(inst, rr);
            let (rep1, rep2) = (a.reference(2, "rep_1")?, a.reference(3, "rep_2")?);
            let Some(rrt) = inst.part("REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION") else {
                return Ok(Some((rep1, rep2, None)));
            };
            let t = Attrs::of(inst, rrt).reference(0, "transformation_operator")?;
            let (i1, i2) = r.visit(t, id, |_, ti| {
                let ta = Reader::expect_simple(ti, "ITEM_DEFINED_TRANSFORMATION")?;
                Ok((
                    ta.reference(2, "transform_item_1")?,
                    ta.reference(3, "transform_item_2")?,
                ))
            })?;
            Ok(Some((rep1, rep2, Some((i1, i2)))))
        })?;
        match rel {
            Some((a, b, None)) => spaces.join(a, b),
            Some((a, b, Some((i1, i2)))) => with_t.push((id, a, b, i1, i2)),
            None => {}
        }
    }
    let mut out = Vec::new();
    for (id, rep1, rep2, i1, i2) in with_t {
        // rep_1 is the child unless the assembly usage says rep_2 is.
        let child_space = child_pd
            .get(&id)
            .and_then(|pd| pd_rep.get(pd))
            .map(|&rep| spaces.find(rep));
        let rep2_is_child = child_space.is_some_and(|c| c == spaces.find(rep2));
        let (child, parent, cf, pf) = if rep2_is_child {
            (rep2, rep1, i2, i1)
        } else {
            (rep1, rep2, i1, i2)
        };
        out.push(Link {
            child,
            parent,
            child_frame: (cf, items.get(&cf).copied().unwrap_or(child)),
            parent_frame: (pf, items.get(&pf).copied().unwrap_or(parent)),
        });
    }
    for mi in file.ids_of_type("MAPPED_ITEM").collect::<Vec<_>>() {
        let Some(&parent) = items.get(&mi) else {
            continue;
        };
        let (map, target) = r.visit(mi, mi, |_, inst| {
            let a = Attrs::of(inst, &inst.parts[0]);
            Ok((
                a.reference(1, "mapping_source")?,
                a.reference(2, "mapping_target")?,
            ))
        })?;
        let (origin, child) = r.visit(map, mi, |_, inst| {
            let a = Reader::expect_simple(inst, "REPRESENTATION_MAP")?;
            Ok((
                a.reference(0, "mapping_origin")?,
                a.reference(1, "mapped_representation")?,
            ))
        })?;
        out.push(Link {
            child,
            parent,
            child_frame: (origin, child),
            parent_frame: (target, parent),
        });
    }
    Ok(out)
}

/// Reads an axis placement in the units of representation `rep`.
fn frame(
    r: &mut Reader,
    (id, rep): (u64, u64),
    contexts: &BTreeMap<u64, u64>,
) -> Result<Placement, StepError> {
    let (mm, rad) = (r.mm, r.rad);
    if let Some(&ctx) = contexts.get(&rep)
        && let Some(u) = r.context_units(ctx, rep)?
    {
        r.mm = u.mm;
        r.rad = u.rad;
    }
    let f = r.placement(id, rep);
    r.mm = mm;
    r.rad = rad;
    Ok(Placement::of_frame(&f?))
}

/// The placements of the body items `bodies` (solids and shell-based models): one per instance,
/// identity for a body no assembly places.
pub(crate) fn placements(
    file: &StepFile,
    r: &mut Reader,
    bodies: &[u64],
) -> Result<BTreeMap<u64, Vec<Placement>>, StepError> {
    let items = items_of(file, r)?;
    let mut spaces = Spaces(BTreeMap::new());
    // Spaces: representations linked without a transformation.
    for srr in file
        .ids_of_type("SHAPE_REPRESENTATION_RELATIONSHIP")
        .chain(file.ids_of_type("REPRESENTATION_RELATIONSHIP"))
        .collect::<Vec<_>>()
    {
        let (a, b) = r.visit(srr, srr, |_, inst| {
            let a = Attrs::of(inst, &inst.parts[0]);
            Ok((a.reference(2, "rep_1")?, a.reference(3, "rep_2")?))
        })?;
        spaces.join(a, b);
    }
    let links = links(file, r, &items, &mut spaces)?;
    // The context of each representation, for the units its placements are in.
    let mut contexts: BTreeMap<u64, u64> = BTreeMap::new();
    for t in REPRESENTATIONS {
        for rep in file.ids_of_type(t).collect::<Vec<_>>() {
            let ctx = r.visit(rep, rep, |_, inst| {
                Attrs::of(inst, &inst.parts[0]).reference(2, "context_of_items")
            })?;
            contexts.insert(rep, ctx);
        }
    }
    // Parent links of each space, with the child-to-parent placement.
    let mut up: BTreeMap<u64, Vec<(u64, Placement)>> = BTreeMap::new();
    for l in &links {
        let c = frame(r, l.child_frame, &contexts)?;
        let p = frame(r, l.parent_frame, &contexts)?;
        let t = p.then_outer(&c.inverse());
        let (cs, ps) = (spaces.find(l.child), spaces.find(l.parent));
        if cs != ps {
            up.entry(cs).or_default().push((ps, t));
        }
    }
    let mut out = BTreeMap::new();
    for &b in bodies {
        let start = items.get(&b).map(|&rep| spaces.find(rep));
        let mut found: Vec<Placement> = Vec::new();
        if let Some(s) = start {
            // Every path up to a root: the body's placements in the world.
            let mut stack: Vec<(u64, Placement, usize)> = vec![(s, Placement::IDENTITY, 0)];
            while let Some((space, acc, depth)) = stack.pop() {
                match up.get(&space) {
                    Some(parents) if depth < MAX_DEPTH => {
                        for (p, t) in parents.iter().rev() {
                            stack.push((*p, t.then_outer(&acc), depth + 1));
                        }
                    }
                    Some(_) => {
                        return Err(StepError::entity(
                            b,
                            "(assembly)",
                            format!("assemblies nest deeper than {MAX_DEPTH} (or in a cycle)"),
                        ));
                    }
                    None => found.push(acc),
                }
                if found.len() > MAX_INSTANCES {
                    return Err(StepError::entity(
                        b,
                        "(assembly)",
                        format!("more than {MAX_INSTANCES} instances"),
                    ));
                }
            }
        }
        if found.is_empty() {
            found.push(Placement::IDENTITY);
        }
        out.insert(b, found);
    }
    Ok(out)
}

/// The name a body item gives itself (its first attribute).
pub(crate) fn body_name(r: &mut Reader, body: u64) -> String {
    r.visit(body, body, |_, inst| match inst.parts[0].params.first() {
        Some(Value::Str(s)) => Ok(s.to_string()),
        _ => Ok(String::new()),
    })
    .unwrap_or_default()
}
