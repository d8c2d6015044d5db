//! probe
use crate::common;

#[test]
fn probe_bound() {
    let model = common::shipped("zhang2013_sector.tsf");
    let region = model.spec.plant_region.clone().unwrap();
    let t = std::time::Instant::now();
    let b = tsfc::model::error_bound::bound(&model, &model.spec, &region, &Default::default()).unwrap();
    eprintln!("{:?} a {:e} b {:e} d {:?} boxes {} conv {} premise {:?} in {:?}", region, b.a_norm, b.b_norm, b.d_norm, b.boxes, b.converged, b.premise, t.elapsed());
    eprintln!("{}", b.a_entry);
}
