//! Laying an [`Animation`] out as glTF: accessors, meshes, nodes and animation channels in
//! gltf-json's structures, the binary data in one buffer, and the whole as GLB through the gltf crate.

use std::borrow::Cow;
use std::collections::BTreeMap;

use ::gltf::json;
use anima_geom::DVec3;
use glam::DQuat;
use json::accessor::{ComponentType, GenericComponentType, Type};
use json::animation::{Interpolation, Property};
use json::validation::{Checked::Valid, USize64};
use json::{Index, Value};

use super::{Animation, DeformingMesh, Figure, RemeshedMesh, StaticMesh, UpAxis};
use crate::VizError;

pub(super) fn write_glb(anim: &Animation, w: impl std::io::Write) -> Result<(), VizError> {
    let mut b = Builder::new();
    let up = anim.up;
    for s in &anim.statics {
        static_mesh(&mut b, up, s);
    }
    for d in anim.deforming.iter().filter(|d| d.n_frames() > 0) {
        deforming_mesh(&mut b, up, d);
    }
    for r in anim.remeshed.iter().filter(|r| r.n_frames() > 0) {
        remeshed_mesh(&mut b, up, r);
    }
    for f in anim.figures.iter().filter(|f| f.n_frames() > 0) {
        figure(&mut b, up, f);
    }
    b.finish(w)
}

/// The file being built: the JSON document, the binary chunk, the scene's root nodes and the one
/// animation's channels and samplers.
struct Builder {
    root: json::Root,
    bin: Vec<u8>,
    buffer: Index<json::Buffer>,
    scene_nodes: Vec<Index<json::Node>>,
    channels: Vec<json::animation::Channel>,
    samplers: Vec<json::animation::Sampler>,
    materials: Vec<([u8; 3], Index<json::Material>)>,
}

impl Builder {
    fn new() -> Self {
        let mut root = json::Root::default();
        root.asset.generator = Some(format!("anima {}", env!("CARGO_PKG_VERSION")));
        // The length is set at the end, when the binary chunk is complete.
        let buffer = root.push(json::Buffer {
            byte_length: USize64(0),
            name: None,
            uri: None,
            extensions: Default::default(),
            extras: Default::default(),
        });
        Self {
            root,
            bin: Vec::new(),
            buffer,
            scene_nodes: Vec::new(),
            channels: Vec::new(),
            samplers: Vec::new(),
            materials: Vec::new(),
        }
    }

    /// A buffer view of its own for `data` (every accessor gets one, so none needs a byte stride),
    /// starting on a 4-byte boundary as glTF asks of f32 and u32 data.
    fn view(&mut self, data: &[u8], target: Option<json::buffer::Target>) -> Index<json::buffer::View> {
        debug_assert!(self.bin.len().is_multiple_of(4));
        let offset = self.bin.len();
        self.bin.extend_from_slice(data);
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        self.root.push(json::buffer::View {
            buffer: self.buffer,
            byte_length: USize64::from(data.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: Default::default(),
            extras: Default::default(),
        })
    }

    fn accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        type_: Type,
        component: ComponentType,
        target: Option<json::buffer::Target>,
        bounds: Option<(Value, Value)>,
    ) -> Index<json::Accessor> {
        let view = self.view(bytes, target);
        let (min, max) = bounds.unzip();
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Valid(GenericComponentType(component)),
            type_: Valid(type_),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
            extensions: Default::default(),
            extras: Default::default(),
        })
    }

    /// Vertex positions (or morph displacements) with the exact bounds of their f32 values, which a
    /// validator checks against the data.
    fn positions(&mut self, p: &[[f32; 3]]) -> Index<json::Accessor> {
        let (mut min, mut max) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for v in p {
            for i in 0..3 {
                min[i] = min[i].min(v[i]);
                max[i] = max[i].max(v[i]);
            }
        }
        let bounds = (Value::from(min.to_vec()), Value::from(max.to_vec()));
        let bytes = f32_bytes(p.iter().flatten().copied());
        self.accessor(
            &bytes,
            p.len(),
            Type::Vec3,
            ComponentType::F32,
            Some(json::buffer::Target::ArrayBuffer),
            Some(bounds),
        )
    }

    fn indices(&mut self, triangles: &[[u32; 3]]) -> Index<json::Accessor> {
        let bytes: Vec<u8> = triangles.iter().flatten().flat_map(|i| i.to_le_bytes()).collect();
        self.accessor(
            &bytes,
            3 * triangles.len(),
            Type::Scalar,
            ComponentType::U32,
            Some(json::buffer::Target::ElementArrayBuffer),
            None,
        )
    }

    /// An animation input: times in s, increasing, with their bounds (glTF requires them).
    fn times(&mut self, t: &[f32]) -> Index<json::Accessor> {
        let bounds = (Value::from(vec![t[0]]), Value::from(vec![t[t.len() - 1]]));
        self.accessor(
            &f32_bytes(t.iter().copied()),
            t.len(),
            Type::Scalar,
            ComponentType::F32,
            None,
            Some(bounds),
        )
    }

    /// An animation output: `values` flattened, `width` floats per key.
    fn output(&mut self, values: &[f32], type_: Type) -> Index<json::Accessor> {
        let width = match type_ {
            Type::Scalar => 1,
            Type::Vec3 => 3,
            Type::Vec4 => 4,
            _ => unreachable!("animation outputs are scalars, vec3 or vec4"),
        };
        self.accessor(
            &f32_bytes(values.iter().copied()),
            values.len() / width,
            type_,
            ComponentType::F32,
            None,
            None,
        )
    }

    /// A material of this sRGB colour, made once per colour. Two-sided: cloth has no inside, and a
    /// closed object looks the same either way.
    fn material(&mut self, colour: [u8; 3]) -> Index<json::Material> {
        if let Some((_, m)) = self.materials.iter().find(|(c, _)| *c == colour) {
            return *m;
        }
        let [r, g, b] = colour.map(srgb_to_linear);
        let m = self.root.push(json::Material {
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor([r, g, b, 1.0]),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(0.8),
                ..Default::default()
            },
            double_sided: true,
            ..Default::default()
        });
        self.materials.push((colour, m));
        m
    }

    /// A mesh of one triangle primitive; `targets` are morph displacements of the positions.
    fn mesh(
        &mut self,
        name: &str,
        positions: Index<json::Accessor>,
        indices: Index<json::Accessor>,
        colour: [u8; 3],
        targets: Vec<Index<json::Accessor>>,
    ) -> Index<json::Mesh> {
        let material = self.material(colour);
        let n_targets = targets.len();
        let targets = (n_targets > 0).then(|| {
            targets
                .into_iter()
                .map(|t| json::mesh::MorphTarget { positions: Some(t), normals: None, tangents: None })
                .collect()
        });
        self.root.push(json::Mesh {
            name: Some(name.to_owned()),
            primitives: vec![json::mesh::Primitive {
                attributes: BTreeMap::from([(Valid(json::mesh::Semantic::Positions), positions)]),
                indices: Some(indices),
                material: Some(material),
                mode: Valid(json::mesh::Mode::Triangles),
                targets,
                extensions: Default::default(),
                extras: Default::default(),
            }],
            weights: (n_targets > 0).then(|| vec![0.0; n_targets]),
            extensions: Default::default(),
            extras: Default::default(),
        })
    }

    fn node(&mut self, node: json::Node) -> Index<json::Node> {
        self.root.push(node)
    }

    /// A track: `output` keyed by `input` times, driving `path` of `node`.
    fn track(
        &mut self,
        node: Index<json::Node>,
        path: Property,
        interpolation: Interpolation,
        input: Index<json::Accessor>,
        output: Index<json::Accessor>,
    ) {
        let sampler = Index::new(self.samplers.len() as u32);
        self.samplers.push(json::animation::Sampler {
            input,
            interpolation: Valid(interpolation),
            output,
            extensions: Default::default(),
            extras: Default::default(),
        });
        self.channels.push(json::animation::Channel {
            sampler,
            target: json::animation::Target {
                node,
                path: Valid(path),
                extensions: Default::default(),
                extras: Default::default(),
            },
            extensions: Default::default(),
            extras: Default::default(),
        });
    }

    fn finish(mut self, w: impl std::io::Write) -> Result<(), VizError> {
        if !self.channels.is_empty() {
            self.root.push(json::Animation {
                name: Some("anima".to_owned()),
                channels: std::mem::take(&mut self.channels),
                samplers: std::mem::take(&mut self.samplers),
                extensions: Default::default(),
                extras: Default::default(),
            });
        }
        // A scene lists at least one node (and readers insist): an animation of nothing has none.
        if !self.scene_nodes.is_empty() {
            let scene = self.root.push(json::Scene {
                name: Some("anima".to_owned()),
                nodes: std::mem::take(&mut self.scene_nodes),
                extensions: Default::default(),
                extras: Default::default(),
            });
            self.root.scene = Some(scene);
        }
        if self.bin.is_empty() {
            // A buffer of no bytes is invalid glTF: an animation of nothing has no buffer.
            self.root.buffers.clear();
        } else {
            self.root.buffers[0].byte_length = USize64::from(self.bin.len());
        }
        let json = json::serialize::to_vec(&self.root).map_err(|e| VizError::GltfWrite(e.into()))?;
        // 12 bytes of header, 8 per chunk header, each chunk padded to 4 bytes.
        let bytes = 12 + 8 + json.len().next_multiple_of(4) as u64 + 8 + self.bin.len() as u64;
        let length = u32::try_from(bytes).map_err(|_| VizError::GltfTooLarge { bytes })?;
        let glb = ::gltf::binary::Glb {
            header: ::gltf::binary::Header { magic: *b"glTF", version: 2, length },
            json: Cow::Owned(json),
            bin: (!self.bin.is_empty()).then_some(Cow::Owned(self.bin)),
        };
        glb.to_writer(w).map_err(|e| match e {
            ::gltf::Error::Io(e) => VizError::GltfWrite(e),
            other => VizError::GltfWrite(std::io::Error::other(other.to_string())),
        })
    }
}

fn f32_bytes(values: impl Iterator<Item = f32>) -> Vec<u8> {
    values.flat_map(f32::to_le_bytes).collect()
}

/// glTF's colour factors are linear; anima's colours are sRGB bytes.
fn srgb_to_linear(c: u8) -> f32 {
    let c = f64::from(c) / 255.0;
    let l = if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) };
    l as f32
}

fn static_mesh(b: &mut Builder, up: UpAxis, s: &StaticMesh) {
    if s.mesh.triangles().is_empty() {
        return;
    }
    let p: Vec<[f32; 3]> = s.mesh.vertices().iter().map(|v| up.to_gltf(v.as_vec3().to_array())).collect();
    let positions = b.positions(&p);
    let indices = b.indices(s.mesh.triangles());
    let mesh = b.mesh(&s.name, positions, indices, s.colour, Vec::new());
    let node = b.node(json::Node { mesh: Some(mesh), name: Some(s.name.clone()), ..Default::default() });
    b.scene_nodes.push(node);
}

/// Frame 0 as the base, each later frame k as morph target k − 1 (p_k − p_0, rounded once to f32),
/// and a LINEAR weights track that is one-hot on target k − 1 at frame k's time.
fn deforming_mesh(b: &mut Builder, up: UpAxis, d: &DeformingMesh) {
    let n = d.n_frames();
    let base: Vec<[f32; 3]> = d.frame(0).iter().map(|&p| up.to_gltf(p)).collect();
    let positions = b.positions(&base);
    let targets: Vec<_> = (1..n)
        .map(|k| {
            let disp: Vec<[f32; 3]> = d
                .frame(k)
                .iter()
                .zip(&base)
                .map(|(&p, q)| {
                    let p = up.to_gltf(p);
                    [0, 1, 2].map(|i| (f64::from(p[i]) - f64::from(q[i])) as f32)
                })
                .collect();
            b.positions(&disp)
        })
        .collect();
    let indices = b.indices(&d.triangles);
    let mesh = b.mesh(d.name(), positions, indices, d.colour, targets);
    let node = b.node(json::Node { mesh: Some(mesh), name: Some(d.name().to_owned()), ..Default::default() });
    b.scene_nodes.push(node);
    if n > 1 {
        let input = b.times(d.times());
        let mut weights = vec![0.0f32; n * (n - 1)];
        for k in 1..n {
            weights[k * (n - 1) + (k - 1)] = 1.0;
        }
        let output = b.output(&weights, Type::Scalar);
        b.track(node, Property::MorphTargetWeights, Interpolation::Linear, input, output);
    }
}

/// A parent node holding one node per frame, each with its own mesh and a STEP scale track of at most
/// three keys: 0 at the previous frame's time, 1 at its own, 0 at the next one's.
fn remeshed_mesh(b: &mut Builder, up: UpAxis, r: &RemeshedMesh) {
    let n = r.frames.len();
    let times: Vec<f32> = r.frames.iter().map(|f| f.time).collect();
    let mut children = Vec::with_capacity(n);
    for (k, f) in r.frames.iter().enumerate() {
        let p: Vec<[f32; 3]> = f.positions.iter().map(|&p| up.to_gltf(p)).collect();
        let positions = b.positions(&p);
        let indices = b.indices(&f.triangles);
        let name = format!("{} frame {k}", r.name);
        let mesh = b.mesh(&name, positions, indices, r.colour, Vec::new());
        let shown = if k == 0 { 1.0 } else { 0.0 };
        let node = b.node(json::Node {
            mesh: Some(mesh),
            name: Some(name),
            scale: Some([shown; 3]),
            ..Default::default()
        });
        if n > 1 {
            let (keys, scales): (std::ops::Range<usize>, &[f32]) = if k == 0 {
                (0..2, &[1.0, 0.0])
            } else if k == n - 1 {
                (n - 2..n, &[0.0, 1.0])
            } else {
                (k - 1..k + 2, &[0.0, 1.0, 0.0])
            };
            let input = b.times(&times[keys]);
            let values: Vec<f32> = scales.iter().flat_map(|&s| [s; 3]).collect();
            let output = b.output(&values, Type::Vec3);
            b.track(node, Property::Scale, Interpolation::Step, input, output);
        }
        children.push(node);
    }
    let parent =
        b.node(json::Node { name: Some(r.name.clone()), children: Some(children), ..Default::default() });
    b.scene_nodes.push(parent);
}

/// A node for the figure, a node per link parented as the skeleton, and per link LINEAR translation
/// and rotation tracks of its pose relative to its parent.
fn figure(b: &mut Builder, up: UpAxis, f: &Figure) {
    let n_links = f.links.len();
    let n = f.n_frames();
    // Local poses in glTF's axes, frame after frame, link after link.
    let world = |k: usize, i: usize| {
        let p = f.frame(k)[i];
        (DVec3::from_array(up.to_gltf(p.translation.to_array())), up.rotation_to_gltf(p.rotation))
    };
    let mut translations = vec![vec![0.0f32; 3 * n]; n_links];
    let mut rotations = vec![vec![0.0f32; 4 * n]; n_links];
    for (i, link) in f.links.iter().enumerate() {
        let mut previous: Option<DQuat> = None;
        for k in 0..n {
            let (t, q) = world(k, i);
            let (t, mut q) = match link.parent {
                None => (t, q),
                Some(p) => {
                    let (tp, qp) = world(k, p);
                    let inv = qp.inverse();
                    (inv * (t - tp), (inv * q).normalize())
                }
            };
            // q and −q are one rotation; the slerp between keys takes the short way only when
            // consecutive keys lie in one hemisphere.
            if previous.is_some_and(|prev| prev.dot(q) < 0.0) {
                q = -q;
            }
            previous = Some(q);
            translations[i][3 * k..3 * k + 3].copy_from_slice(&t.as_vec3().to_array());
            rotations[i][4 * k..4 * k + 4].copy_from_slice(&q.as_quat().to_array());
        }
    }
    let nodes: Vec<Index<json::Node>> = f
        .links
        .iter()
        .enumerate()
        .map(|(i, link)| {
            let p: Vec<[f32; 3]> =
                link.shape.vertices().iter().map(|v| up.to_gltf(v.as_vec3().to_array())).collect();
            let mesh = (!link.shape.triangles().is_empty()).then(|| {
                let positions = b.positions(&p);
                let indices = b.indices(link.shape.triangles());
                b.mesh(&link.name, positions, indices, link.colour, Vec::new())
            });
            let t = &translations[i];
            let q = &rotations[i];
            b.node(json::Node {
                mesh,
                name: Some(link.name.clone()),
                translation: Some([t[0], t[1], t[2]]),
                rotation: Some(json::scene::UnitQuaternion([q[0], q[1], q[2], q[3]])),
                ..Default::default()
            })
        })
        .collect();
    // Children lists, now that every link has its node.
    for (i, link) in f.links.iter().enumerate() {
        if let Some(p) = link.parent {
            b.root.nodes[nodes[p].value()].children.get_or_insert_with(Vec::new).push(nodes[i]);
        }
    }
    let roots =
        f.links.iter().enumerate().filter(|(_, l)| l.parent.is_none()).map(|(i, _)| nodes[i]).collect();
    let node = b.node(json::Node { name: Some(f.name.clone()), children: Some(roots), ..Default::default() });
    b.scene_nodes.push(node);
    if n > 1 {
        let input = b.times(&f.times);
        for (i, &node) in nodes.iter().enumerate() {
            let t = b.output(&translations[i], Type::Vec3);
            b.track(node, Property::Translation, Interpolation::Linear, input, t);
            let q = b.output(&rotations[i], Type::Vec4);
            b.track(node, Property::Rotation, Interpolation::Linear, input, q);
        }
    }
}
