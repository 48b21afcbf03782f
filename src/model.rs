//! The immutable model of one drillstring in one well: nodes along the well path, beam
//! elements between them, contact sites, loads and boundary conditions (paper §3.1).
//!
//! Nodes are numbered from the surface (node 0, MD 0) to the bit (last node). The string is
//! meshed on the hole axis, so each node's initial position is its contact site's
//! reference point `x0`.

use crate::physics::beam::{BeamSection, Mat3};
use crate::physics::contact::{ContactParams, FrictionModel};
use crate::physics::vec3::{cross, dot, scale, sub, Vec3};
use crate::well::WellPath;

/// Standard gravity (m/s²).
pub const GRAVITY: f64 = 9.806_65;

/// One node.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// Measured depth (m).
    pub md: f64,
    /// Initial position (on the hole axis).
    pub position: Vec3<f64>,
    /// Unit hole axis at the node, pointing down-hole.
    pub hole_axis: Vec3<f64>,
    /// Reference triad of the node in the natural (straight, unstressed) string: first axis
    /// along the hole axis, the others carried along the well by parallel transport (no
    /// twist). Element triads are `R_i · frame0`: a string meshed into a curved hole is bent
    /// there (moment ≈ EI·κ), as a straight pipe forced into the hole is.
    pub frame0: Mat3<f64>,
}

/// One beam element between nodes `i` and `i + 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct Element {
    /// Section and material.
    pub section: BeamSection,
    /// Initial length (m).
    pub length0: f64,
    /// Initial frame, columns `e1` (node i → i+1), `e2`, `e3`.
    pub frame0: Mat3<f64>,
    /// Buoyed weight per length (N/m): `ρ_steel A g (1 − ρ_mud/ρ_steel)`.
    pub buoyed_weight_per_length: f64,
    /// Air weight per length (N/m).
    pub air_weight_per_length: f64,
    /// Outer diameter of the body (m), for stresses and buoyancy.
    pub outer_diameter: f64,
    /// Diameter where the element touches the wall (m): its tool joints' OD (issue 26), or
    /// the body's — the soft string's torque arm, the buckling clearance, a joint node's
    /// contact disk.
    pub contact_diameter: f64,
    /// Index of the string component the element belongs to.
    pub component: usize,
}

impl Element {
    /// The bore's diameter (m), from the body's OD and the steel area.
    pub fn inner_diameter(&self) -> f64 {
        (self.outer_diameter * self.outer_diameter
            - self.section.area / std::f64::consts::FRAC_PI_4)
            .max(0.0)
            .sqrt()
    }
}

/// A contact element at a node (paper §2).
#[derive(Clone, Debug, PartialEq)]
pub struct Site {
    /// Node index.
    pub node: usize,
    /// Hole radius `R_h` (m).
    pub hole_radius: f64,
    /// Law parameters; `clearance = R_h − R_d`, `disk_radius = R_d`.
    pub params: ContactParams<f64>,
    /// Whether the site is a stabilizer (as opposed to pipe body contact).
    pub stabilizer: bool,
}

impl Site {
    /// Whether the turning string whirls here in static mode
    /// ([`crate::diagnose::mark_whirling_sites`]): its circumferential friction acts as
    /// torque alone (`params.side_friction` below 1).
    pub fn whirls(&self) -> bool {
        self.params.side_friction < 1.0
    }
}

/// Top boundary condition.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TopBoundary {
    /// Clamped to the rotary table: all displacements and rotations zero (§3.1).
    Clamped,
    /// Pinned: displacements and the rotation about the hole axis zero, bending rotations
    /// free (closed-form checks: pinned columns).
    Pinned,
    /// Hook load given (N): the top is held laterally and in rotation but free to move
    /// along the (vertical) hole axis, pulled up by the hook load; the bit then rests on
    /// bottom (axially held) and the weight on bit is the reaction there.
    HookLoad(f64),
    /// Nothing held: a free-flying string (closed-form checks of the dynamics: energy of a
    /// spinning, bent string). Statics need another support.
    Free,
}

/// Everything a static or dynamic solve needs.
#[derive(Clone, Debug)]
pub struct Model {
    /// Nodes, surface first.
    pub nodes: Vec<Node>,
    /// Elements, element `i` between nodes `i` and `i + 1`.
    pub elements: Vec<Element>,
    /// Contact sites.
    pub sites: Vec<Site>,
    /// Friction model of every site.
    pub friction: FrictionModel,
    /// Weight on bit (N, compressive force of the rock on the bit).
    pub weight_on_bit: f64,
    /// Torque on bit (N·m, resisting the rotation).
    pub torque_on_bit: f64,
    /// Axial speed of the operation along the hole axis, positive down-hole (m/s): the
    /// friction direction in static analysis (tripping in > 0, out < 0).
    pub axial_speed: f64,
    /// Rotation speed of the operation (rad/s, positive clockwise seen from above).
    pub rotation_speed: f64,
    /// Top boundary condition.
    pub top: TopBoundary,
    /// Whether the bit's displacements perpendicular to the hole axis are held at zero.
    pub bit_lateral_fixed: bool,
    /// Further nodal loads (node, [force (N); moment (N·m)]), scaled with the load factor.
    pub point_loads: Vec<(usize, [f64; 6])>,
    /// Mass imbalance per node (kg·m): the node's mass times the offset of its centre of
    /// mass from the pipe axis, as a vector in the global axes of the initial configuration;
    /// it turns with the node (`R U₀`). Empty: none. Dynamics only (a rigid eccentric mass:
    /// [`crate::solve::dynamics`]).
    pub unbalance: Vec<Vec3<f64>>,
    /// Stress-free kinks (bent subs, bent motor housings). Empty: a straight string.
    pub bends: Vec<Bend>,
}

/// A stress-free kink of the string at a node: the string below it is turned by `angle`
/// from the string above, when unloaded. Carried by the element above the node as its
/// unstrained rotations ([`crate::physics::beam::kink_rest_rotation`]); it turns with the
/// string (a bent sub rotating in the hole forces a whirl).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bend {
    /// The node at the kink (interior: not the top, not the bit).
    pub node: usize,
    /// Bend angle (rad).
    pub angle: f64,
    /// Direction of the bend around the pipe, from the node's reference triad's second axis
    /// towards its third (rad): [`Model::toolface_from_high_side`] converts a toolface
    /// measured from the high side of the hole.
    pub toolface: f64,
}

/// An orthonormal frame whose first column is `e1`.
pub fn frame_from_axis(e1: &Vec3<f64>) -> Mat3<f64> {
    let helper = if e1[2].abs() < 0.9 {
        [0.0, 0.0, 1.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let e2 = cross(&helper, e1);
    let e2 = scale(&e2, 1.0 / dot(&e2, &e2).sqrt());
    let e3 = cross(e1, &e2);
    [
        [e1[0], e2[0], e3[0]],
        [e1[1], e2[1], e3[1]],
        [e1[2], e2[2], e3[2]],
    ]
}

/// Parallel transport of a frame from tangent `t1` to `t2`: the minimal rotation taking
/// `t1` to `t2`, applied to `frame`.
pub fn transport(frame: &Mat3<f64>, t1: &Vec3<f64>, t2: &Vec3<f64>) -> Mat3<f64> {
    let axis = cross(t1, t2);
    let s = dot(&axis, &axis).sqrt();
    let c = dot(t1, t2);
    let angle = s.atan2(c);
    let theta = if s > 0.0 {
        scale(&axis, angle / s)
    } else {
        [0.0; 3]
    };
    let r = crate::physics::beam::rotation_exp(&theta);
    std::array::from_fn(|row| {
        std::array::from_fn(|col| (0..3).map(|k| r[row][k] * frame[k][col]).sum())
    })
}

/// The hole's frame at a point ([`crate::bha`] for the conventions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HoleFrame {
    /// Hole axis, down-hole.
    pub axis: Vec3<f64>,
    /// High side.
    pub high: Vec3<f64>,
    /// Right side, `axis × high`.
    pub right: Vec3<f64>,
}

impl HoleFrame {
    /// The frame at node `node` of `model`: its hole axis, the high side, the right side; in
    /// a vertical hole (inclination below 2·10⁻⁴ °) the node's reference second axis stands for
    /// the high side.
    pub fn at_node(model: &Model, node: usize) -> HoleFrame {
        let nd = &model.nodes[node];
        let t = nd.hole_axis;
        // Up (−z: z points down) perpendicular to the hole axis.
        let up = [t[2] * t[0], t[2] * t[1], t[2] * t[2] - 1.0];
        let n = dot(&up, &up).sqrt();
        let high = if n >= 1e-6 {
            scale(&up, 1.0 / n)
        } else {
            let f = &nd.frame0;
            [f[0][1], f[1][1], f[2][1]]
        };
        HoleFrame {
            axis: t,
            high,
            right: cross(&t, &high),
        }
    }

    /// Components of `v` along (high side, right side).
    pub fn across(&self, v: &Vec3<f64>) -> (f64, f64) {
        (dot(v, &self.high), dot(v, &self.right))
    }

    /// The angles of direction `d` from the hole axis towards the high side and towards the
    /// right side (rad): `atan2(d·h, d·t)` and `atan2(d·r, d·t)`.
    pub fn angles(&self, d: &Vec3<f64>) -> (f64, f64) {
        let a = dot(d, &self.axis);
        (dot(d, &self.high).atan2(a), dot(d, &self.right).atan2(a))
    }
}

/// One tubular of the string: the mesh builder's input.
#[derive(Clone, Debug, PartialEq)]
pub struct Tubular {
    /// Name for reports (e.g. "drill collar").
    pub name: String,
    /// Length (m).
    pub length: f64,
    /// Outer diameter (m).
    pub outer_diameter: f64,
    /// Inner diameter (m).
    pub inner_diameter: f64,
    /// Young's modulus (Pa).
    pub youngs_modulus: f64,
    /// Poisson ratio.
    pub poisson_ratio: f64,
    /// Steel density (kg/m³).
    pub density: f64,
    /// Target element length in this tubular (m).
    pub element_length: f64,
}

/// A vertical string of 6.5 in × 0.071 m collar, `length` m in `elements` equal elements, in
/// mud of `mud_density` (kg/m³): top clamped, bit held laterally ([`Model::bare`]). The
/// mesh of kernel benchmarks, and (in mud as dense as steel: weightless) of closed-form
/// tests.
pub fn vertical_collar(length: f64, elements: usize, mud_density: f64) -> Model {
    let well = WellPath::vertical(length);
    let t = Tubular {
        name: "collar".into(),
        length,
        outer_diameter: 0.165,
        inner_diameter: 0.071,
        youngs_modulus: 2.1e11,
        poisson_ratio: 0.3,
        density: 7850.0,
        element_length: length / elements as f64,
    };
    let (nodes, elements) = mesh_string(&well, &[t], length, mud_density);
    Model::bare(nodes, elements)
}

/// Meshes tubulars listed **from the bit up** along `well`, the bit at `bit_md`. Returns
/// nodes (surface first) and elements, with buoyancy factor `1 − ρ_mud/ρ_steel`.
pub fn mesh_string(
    well: &WellPath,
    tubulars_from_bit: &[Tubular],
    bit_md: f64,
    mud_density: f64,
) -> (Vec<Node>, Vec<Element>) {
    mesh_string_two_fluids(
        well,
        tubulars_from_bit,
        bit_md,
        mud_density,
        mud_density,
        &[],
    )
}

/// How far from a node an MD asked for by [`mesh_string_two_fluids`]'s `nodes_at` may
/// stand, and the shortest element the asked nodes make (m). The asked MDs are taken in
/// clusters no wider than twice this, a node at each cluster's middle ([`nodes_at_kept`]);
/// one closer than this to a component's end takes that end's node, and an evenly spaced
/// node closer than this to an asked one gives way to it. A stabilizer an ensemble places
/// (`stabK.from_bit`) then stands within this of where its variant puts it.
pub const NODE_AT_GAP: f64 = 0.1;

/// The MDs at which [`mesh_string_two_fluids`] puts nodes for those asked (`wanted`), in
/// ascending order: the middles of clusters of the asked no wider than twice
/// [`NODE_AT_GAP`] (each asked MD within the gap of its node; neighbouring nodes more than
/// the gap apart).
pub fn nodes_at_kept(wanted: &[f64]) -> Vec<f64> {
    let mut sorted: Vec<f64> = wanted.iter().copied().filter(|x| x.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    let mut kept = Vec::new();
    let mut i = 0;
    while i < sorted.len() {
        let first = sorted[i];
        let mut last = first;
        while i < sorted.len() && sorted[i] - first <= 2.0 * NODE_AT_GAP {
            last = sorted[i];
            i += 1;
        }
        kept.push(0.5 * (first + last));
    }
    kept
}

/// How many of `tubulars_from_bit` the string takes from the bit at `bit_md` up to the
/// surface: the components listed above the one that reaches it lie above the surface and
/// are left out of the mesh ([`mesh_string`]; the case reader warns of them).
pub fn components_in_hole(tubulars_from_bit: &[Tubular], bit_md: f64) -> usize {
    let mut bottom = bit_md;
    tubulars_from_bit
        .iter()
        .take_while(|t| {
            let below_surface = bottom > 0.0;
            bottom -= t.length;
            below_surface
        })
        .count()
}

/// [`mesh_string`] with one fluid in the annulus (`outside`, kg/m³) and another inside the
/// string (`inside`): the buoyed weight per length from the two columns,
/// `g (ρ_s A_s + ρ_i A_i − ρ_o A_o)` (`A_i`, `A_o` the bore's and the outer diameter's areas;
/// Lubinski's effective force then carries the two pressures). Equal fluids give
/// `ρ_s A_s g (1 − ρ/ρ_s)`.
///
/// `nodes_at`: MDs that are to have a node (a stabilizer an ensemble places there): a node
/// at each of [`nodes_at_kept`] that lies inside a component more than [`NODE_AT_GAP`] from
/// its ends; the component's evenly spaced nodes within the gap of one give way.
pub fn mesh_string_two_fluids(
    well: &WellPath,
    tubulars_from_bit: &[Tubular],
    bit_md: f64,
    outside: f64,
    inside: f64,
    nodes_at: &[f64],
) -> (Vec<Node>, Vec<Element>) {
    let wanted = nodes_at_kept(nodes_at);
    // MD breakpoints from the top down.
    let mut pieces: Vec<(usize, f64, f64)> = Vec::new(); // (component, top md, bottom md)
    let mut bottom = bit_md;
    let in_hole = components_in_hole(tubulars_from_bit, bit_md);
    for (k, t) in tubulars_from_bit[..in_hole].iter().enumerate() {
        let top = (bottom - t.length).max(0.0);
        pieces.push((k, top, bottom));
        bottom = top;
    }
    pieces.reverse();
    let mut mds = vec![pieces.first().map(|p| p.1).unwrap_or(0.0)];
    let mut owner = Vec::new();
    for &(k, top, bot) in &pieces {
        let n = ((bot - top) / tubulars_from_bit[k].element_length)
            .ceil()
            .max(1.0) as usize;
        let asked: Vec<f64> = wanted
            .iter()
            .copied()
            .filter(|&md| md > top + NODE_AT_GAP && md < bot - NODE_AT_GAP)
            .collect();
        let mut points: Vec<f64> = (1..=n)
            .map(|j| top + (bot - top) * j as f64 / n as f64)
            .filter(|&p| p == bot || asked.iter().all(|&a| (p - a).abs() >= NODE_AT_GAP))
            .collect();
        points.extend(&asked);
        points.sort_by(f64::total_cmp);
        for p in points {
            mds.push(p);
            owner.push(k);
        }
    }
    let mut nodes: Vec<Node> = mds
        .iter()
        .map(|&md| {
            let (p, t) = well.at(md);
            Node {
                md,
                position: p,
                hole_axis: t,
                frame0: frame_from_axis(&t),
            }
        })
        .collect();
    for i in 1..nodes.len() {
        nodes[i].frame0 = transport(
            &nodes[i - 1].frame0,
            &nodes[i - 1].hole_axis,
            &nodes[i].hole_axis,
        );
    }
    let elements = owner
        .iter()
        .enumerate()
        .map(|(i, &k)| {
            let t = &tubulars_from_bit[k];
            let d = sub(&nodes[i + 1].position, &nodes[i].position);
            let l0 = dot(&d, &d).sqrt();
            let section = BeamSection::tube(
                t.outer_diameter,
                t.inner_diameter,
                t.youngs_modulus,
                t.poisson_ratio,
            );
            let air = t.density * section.area * GRAVITY;
            Element {
                section,
                length0: l0,
                frame0: frame_from_axis(&scale(&d, 1.0 / l0)),
                buoyed_weight_per_length: {
                    let quarter_pi = std::f64::consts::FRAC_PI_4;
                    let bore = quarter_pi * t.inner_diameter * t.inner_diameter;
                    let outer = quarter_pi * t.outer_diameter * t.outer_diameter;
                    air + GRAVITY * (inside * bore - outside * outer)
                },
                air_weight_per_length: air,
                outer_diameter: t.outer_diameter,
                contact_diameter: t.outer_diameter,
                component: k,
            }
        })
        .collect();
    (nodes, elements)
}

/// Contact law settings shared by the sites of a model (paper Table 1 defaults in the case
/// files).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactSettings {
    /// Wall stiffness `k_e` (N/m^m).
    pub wall_stiffness: f64,
    /// Spring exponent `m`.
    pub spring_exponent: f64,
    /// Wall damping `c` (N·s/m).
    pub wall_damping: f64,
    /// Friction regularisation speed `eps` (m/s).
    pub eps: f64,
    /// Soft-spring blend depth (m).
    pub soft_blend: f64,
}

/// Adds a contact site at every node listed, with hole radius `hole_radius(md)` and disk
/// radius `disk_radius(node)`, friction `mu` (both directions).
pub fn add_sites(
    model: &mut Model,
    nodes: &[usize],
    hole_radius: impl Fn(f64) -> f64,
    disk_radius: impl Fn(usize) -> f64,
    mu: impl Fn(f64) -> f64,
    settings: &ContactSettings,
    stabilizer: bool,
) {
    for &i in nodes {
        let md = model.nodes[i].md;
        let rh = hole_radius(md);
        let rd = disk_radius(i);
        let mu = mu(md);
        model.sites.push(Site {
            node: i,
            hole_radius: rh,
            params: ContactParams {
                clearance: rh - rd,
                disk_radius: rd,
                wall_stiffness: settings.wall_stiffness,
                spring_exponent: settings.spring_exponent,
                wall_damping: settings.wall_damping,
                mu_t: mu,
                mu_l: mu,
                eps: settings.eps,
                soft_blend: settings.soft_blend,
                side_friction: 1.0,
            },
            stabilizer,
        });
    }
}

/// The one name of stabilizer `number` (1 = nearest the bit) in every output: plot labels,
/// file names, CSV columns, ensemble keys (`stab1.from_bit`) and messages.
pub fn stabilizer_name(number: usize) -> String {
    format!("stab{number}")
}

impl Model {
    /// Per node, whether a contact site holds it.
    pub fn site_nodes(&self) -> Vec<bool> {
        let mut held = vec![false; self.nodes.len()];
        for s in &self.sites {
            held[s.node] = true;
        }
        held
    }

    /// The stabilizer sites (indices into `sites`), **nearest the bit first**: stabilizer
    /// number `k` (1-based, as in [`stabilizer_name`]) is entry `k − 1`. The one numbering
    /// every output uses.
    pub fn stabilizer_sites(&self) -> Vec<usize> {
        let mut s: Vec<usize> = (0..self.sites.len())
            .filter(|&k| self.sites[k].stabilizer)
            .collect();
        s.sort_by_key(|&k| std::cmp::Reverse(self.sites[k].node));
        s
    }

    /// Each contact site's stabilizer number (1 = nearest the bit; 0 for a pipe-body
    /// site), indexed like `sites`: computed once for a table of many rows.
    pub fn stabilizer_numbers(&self) -> Vec<usize> {
        let mut numbers = vec![0; self.sites.len()];
        for (k, &site) in self.stabilizer_sites().iter().enumerate() {
            numbers[site] = k + 1;
        }
        numbers
    }

    /// The length of string a node stands for: half of each adjacent element (m); a side
    /// force over it is the force per unit length.
    pub fn tributary_length(&self, node: usize) -> f64 {
        let n = self.nodes.len();
        let mut l = 0.0;
        if node > 0 {
            l += 0.5 * self.elements[node - 1].length0;
        }
        if node + 1 < n {
            l += 0.5 * self.elements[node].length0;
        }
        l.max(1e-9)
    }
    /// The string from node `first` to the bit: its nodes and elements, and the contact
    /// sites, bends, point loads and imbalance below `first` renumbered; the top clamped
    /// there (`first = 0`: the whole string, its own top) and the bit held laterally. The
    /// BHA models of the tendency and the critical speeds start here.
    pub fn lower_part(&self, first: usize) -> Model {
        Model {
            nodes: self.nodes[first..].to_vec(),
            elements: self.elements[first..].to_vec(),
            sites: self
                .sites
                .iter()
                .filter(|s| s.node > first)
                .map(|s| Site {
                    node: s.node - first,
                    ..s.clone()
                })
                .collect(),
            top: if first == 0 {
                self.top
            } else {
                TopBoundary::Clamped
            },
            bit_lateral_fixed: true,
            point_loads: self
                .point_loads
                .iter()
                .filter(|(k, _)| *k > first)
                .map(|(k, f)| (k - first, *f))
                .collect(),
            unbalance: self.unbalance.get(first..).map_or(vec![], |u| u.to_vec()),
            bends: self
                .bends
                .iter()
                .filter(|b| b.node > first)
                .map(|b| Bend {
                    node: b.node - first,
                    ..*b
                })
                .collect(),
            ..self.clone()
        }
    }

    /// A model of the mesh with no contact sites or loads: top clamped, bit held laterally,
    /// split friction, no operation.
    pub fn bare(nodes: Vec<Node>, elements: Vec<Element>) -> Model {
        Model {
            nodes,
            elements,
            sites: vec![],
            friction: FrictionModel::Split,
            weight_on_bit: 0.0,
            torque_on_bit: 0.0,
            axial_speed: 0.0,
            rotation_speed: 0.0,
            top: TopBoundary::Clamped,
            bit_lateral_fixed: true,
            point_loads: vec![],
            unbalance: vec![],
            bends: vec![],
        }
    }

    /// Element `i`'s stiffnesses and unstrained rotations (a kink at its lower node, if
    /// any): what every CPU element evaluation uses.
    pub fn element_stiffness(&self, i: usize) -> crate::physics::beam::ElementStiffness<f64> {
        let e = &self.elements[i];
        let k = crate::physics::beam::ElementStiffness::of(&e.section, e.length0);
        // The first bend at this element, as `kinks(1.0)` lists them (called per element
        // and evaluation: the others' rest rotations are not formed).
        match self.bends.iter().find(|b| b.node - 1 == i) {
            Some(b) => k.with_rest(self.kink(b, 1.0).1),
            None => k,
        }
    }

    /// The kinked elements and their unstrained rotations, the bends' angles scaled by
    /// `scale` (the static load factor; 1: in full): the one place a [`Bend`] becomes an
    /// element's rest state, for the CPU solvers and the kernels' `rest` table alike.
    pub fn kinks(&self, scale: f64) -> Vec<(usize, [[f64; 3]; 2])> {
        self.bends.iter().map(|b| self.kink(b, scale)).collect()
    }

    /// The kinked element of bend `b` and its unstrained rotations at `scale`.
    fn kink(&self, b: &Bend, scale: f64) -> (usize, [[f64; 3]; 2]) {
        let e = b.node - 1;
        let rest = crate::physics::beam::kink_rest_rotation(
            scale * b.angle,
            b.toolface,
            self.elements[e].length0,
        );
        (e, rest)
    }

    /// The unstrained nodal rotations of element `i` (zero but at a kink).
    pub fn element_rest(&self, i: usize) -> [[f64; 3]; 2] {
        self.element_stiffness(i).rest
    }

    /// A toolface measured from the high side of the hole at `node` (clockwise looking
    /// down-hole; a vertical hole: from the node's reference second axis) as the angle
    /// [`Bend::toolface`] takes.
    pub fn toolface_from_high_side(&self, node: usize, from_high_side: f64) -> f64 {
        let frame = HoleFrame::at_node(self, node);
        let f = &self.nodes[node].frame0;
        let (a2, a3) = ([f[0][1], f[1][1], f[2][1]], [f[0][2], f[1][2], f[2][2]]);
        let (c, s) = (from_high_side.cos(), from_high_side.sin());
        let d: Vec3<f64> = std::array::from_fn(|k| c * frame.high[k] + s * frame.right[k]);
        dot(&d, &a3).atan2(dot(&d, &a2))
    }

    /// The inverse of [`Model::toolface_from_high_side`]: a [`Bend::toolface`] at `node` as a
    /// toolface from the high side (rad).
    pub fn toolface_to_high_side(&self, node: usize, toolface: f64) -> f64 {
        let frame = HoleFrame::at_node(self, node);
        let f = &self.nodes[node].frame0;
        let d: Vec3<f64> =
            std::array::from_fn(|k| toolface.cos() * f[k][1] + toolface.sin() * f[k][2]);
        let (h, r) = frame.across(&d);
        r.atan2(h)
    }

    /// The nodal mass imbalance (kg·m vectors, [`Model::unbalance`]) of elements whose
    /// centre of mass sits `eccentricity(e)` (m) off the pipe axis, each towards its frame's
    /// first lateral axis (transported along the hole: one side of a component): half of
    /// each element's steel mass (`density(e)`) to each of its nodes.
    pub fn unbalance_from(
        &self,
        density: &dyn Fn(usize) -> f64,
        eccentricity: &dyn Fn(usize) -> f64,
    ) -> Vec<Vec3<f64>> {
        let mut u = vec![[0.0; 3]; self.nodes.len()];
        for (i, e) in self.elements.iter().enumerate() {
            let ecc = eccentricity(i);
            if ecc == 0.0 {
                continue;
            }
            let half = 0.5 * density(i) * e.section.area * e.length0;
            for node in [i, i + 1] {
                for (k, uk) in u[node].iter_mut().enumerate() {
                    *uk += half * ecc * e.frame0[k][1];
                }
            }
        }
        u
    }

    /// Whether any node carries a mass imbalance.
    pub fn has_unbalance(&self) -> bool {
        self.unbalance.iter().any(|u| u.iter().any(|x| *x != 0.0))
    }

    /// Outer radius of the pipe at node `i` (largest of its elements' contact diameters:
    /// a tool joint's where the string has them at its nodes).
    pub fn pipe_radius_at(&self, i: usize) -> f64 {
        let mut r: f64 = 0.0;
        if i > 0 {
            r = r.max(0.5 * self.elements[i - 1].contact_diameter);
        }
        if i < self.elements.len() {
            r = r.max(0.5 * self.elements[i].contact_diameter);
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::{nodes_at_kept, NODE_AT_GAP};

    /// Each asked MD lies within the gap of a kept one; kept ones lie more than the gap
    /// apart; a lone MD keeps its own node; NaN is dropped.
    #[test]
    fn asked_nodes_are_kept_in_clusters_within_the_gap() {
        let asked = [5.0, 3.0, 3.05, 3.1, 3.15, 3.35, 7.0, f64::NAN, 7.0];
        let kept = nodes_at_kept(&asked);
        let expected = [3.075, 3.35, 5.0, 7.0];
        assert_eq!(kept.len(), expected.len(), "{kept:?}");
        assert!(
            kept.iter()
                .zip(expected)
                .all(|(k, e)| (k - e).abs() < 1e-12),
            "{kept:?}"
        );
        for a in asked.iter().filter(|a| a.is_finite()) {
            let near = kept
                .iter()
                .map(|k| (k - a).abs())
                .fold(f64::INFINITY, f64::min);
            assert!(near <= NODE_AT_GAP + 1e-12, "{a}: {near} from {kept:?}");
        }
        assert!(
            kept.windows(2).all(|w| w[1] - w[0] > NODE_AT_GAP),
            "{kept:?}"
        );
        assert!(nodes_at_kept(&[]).is_empty());
    }
}
