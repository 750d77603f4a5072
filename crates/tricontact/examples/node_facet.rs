//! # A slave node pressed into a facet
//!
//! The smallest complete use of the kernel: one facet, one slave node below it, the penalty force
//! and tangent, and a finite-difference check of that tangent — the check every term of the kernel
//! passes in the test suite.
//!
//! Run with `cargo run --release -p tricontact --example node_facet`. Expected output:
//!
//! ```text
//! facet normal W            = [0.000000, 0.000000, 1.000000]
//! gap P                     = -0.010000
//! shape functions N_i,j,k   = [0.500000, 0.250000, 0.250000]  (sum 1.000000000000)
//! resistance R_l (slave)    = [0.000000, 0.000000, 10.000000]
//! resistance R_i + R_j + R_k = [-0.000000, -0.000000, -10.000000]
//! tangent symmetric         : |K - Kᵀ| = 0.0e0
//! tangent vs central differences: relative error 1.2e-12
//! ```
//!
//! (the last digits of the finite-difference error depend on the platform).

use tricontact::{NodeFacet, Vec3, Vec12, penalty};

fn main() -> Result<(), tricontact::GeometryError> {
    let (xi, xj, xk) = (
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
    );
    let xl = Vec3::new(0.5, 0.5, -0.01);
    let alpha = 1000.0;

    let pair = NodeFacet::new(xi, xj, xk, xl)?;
    let terms = penalty(&pair, alpha)?;
    let n = pair.projection.shape;
    let w = pair.facet.normal();
    println!(
        "facet normal W            = [{:.6}, {:.6}, {:.6}]",
        w.x, w.y, w.z
    );
    println!("gap P                     = {:.6}", pair.gap());
    println!(
        "shape functions N_i,j,k   = [{:.6}, {:.6}, {:.6}]  (sum {:.12})",
        n[0],
        n[1],
        n[2],
        n.iter().sum::<f64>()
    );
    let r = terms.resistance(3);
    println!(
        "resistance R_l (slave)    = [{:.6}, {:.6}, {:.6}]",
        r.x, r.y, r.z
    );
    let r = terms.resistance(0) + terms.resistance(1) + terms.resistance(2);
    println!(
        "resistance R_i + R_j + R_k = [{:.6}, {:.6}, {:.6}]",
        r.x, r.y, r.z
    );
    let k = terms.stiffness;
    println!(
        "tangent symmetric         : |K - Kᵀ| = {:.1e}",
        (k - k.transpose()).amax()
    );

    // Central differences of the force, step 1e-6 of the facet size.
    let mut x = Vec12::zeros();
    for (a, p) in [xi, xj, xk, xl].iter().enumerate() {
        x.fixed_rows_mut::<3>(3 * a).copy_from(p);
    }
    let h = 2e-6;
    let mut fd = tricontact::Mat12::zeros();
    for c in 0..12 {
        let (mut xp, mut xm) = (x, x);
        xp[c] += h;
        xm[c] -= h;
        let fp = penalty(&NodeFacet::from_stacked(&xp)?, alpha)?.force;
        let fm = penalty(&NodeFacet::from_stacked(&xm)?, alpha)?.force;
        fd.set_column(c, &((fp - fm) / (2.0 * h)));
    }
    println!(
        "tangent vs central differences: relative error {:.1e}",
        (fd - k).amax() / k.amax()
    );
    Ok(())
}
