# autobio's Blender worker: builds a scene from the geometry, finishes, lights and cameras autobio
# sends, then draws frames of the poses it sends, with Cycles or Eevee, headless (the `bpy` wheel).
# It is started by `runtime::blender` (runtime/src/blender/worker.rs), which embeds this file, and
# speaks only over its standard input and output:
#
#   message := u32 LE header length | header (JSON) | u64 LE blob length | blob
#
# Requests: {"op": "scene", ...} (geometry; answered {"ok": true}), {"op": "frame", ...} (poses;
# answered with one PNG per camera, concatenated in the blob) and {"op": "quit"}. A failure is
# answered {"ok": false, "error": "..."} and the worker goes on; Blender's own chatter goes to
# standard error, never into the answers.
import json
import math
import os
import shutil
import struct
import sys
import tempfile

ANSWERS = os.fdopen(os.dup(1), "wb")
os.dup2(2, 1)  # Blender prints to fd 1: keep it off the answer channel.
REQUESTS = os.fdopen(os.dup(0), "rb")

import bpy  # noqa: E402
import bmesh  # noqa: E402
import numpy as np  # noqa: E402
from mathutils import Matrix, Vector  # noqa: E402


def read_exact(n):
    out = bytearray()
    while len(out) < n:
        chunk = REQUESTS.read(n - len(out))
        if not chunk:
            return None
        out.extend(chunk)
    return bytes(out)


def receive():
    head = read_exact(4)
    if head is None:
        return None, None
    header = json.loads(read_exact(struct.unpack("<I", head)[0]))
    blob = read_exact(struct.unpack("<Q", read_exact(8))[0])
    return header, blob


def answer(header, blob=b""):
    h = json.dumps(header).encode()
    ANSWERS.write(struct.pack("<I", len(h)) + h + struct.pack("<Q", len(blob)))
    ANSWERS.write(blob)
    ANSWERS.flush()


def array(blob, part, dtype, shape):
    """A typed view of the part (`{"offset", "len"}` in bytes) of the blob."""
    raw = blob[part["offset"] : part["offset"] + part["len"]]
    return np.frombuffer(raw, dtype=dtype).reshape(shape)


def srgb_to_linear(c):
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


class Stage:
    def __init__(self):
        self.objects = []  # one per drawn geom, in the request's order
        self.cameras = []
        self.looks = []  # each object's photoreal material
        self.masks = []  # each object's flat body colour
        self.mode = "photo"
        self.displays = {}  # texture id -> bpy image
        self.tmp = tempfile.mkdtemp(prefix="autobio-blender-")
        self.built = False

    def build(self, spec, blob):
        """The scene anew (a second `scene` request, for a perturbed look, replaces the first).
        Frames are refused until a build has succeeded."""
        self.built = False
        bpy.ops.wm.read_factory_settings(use_empty=True)
        self.objects, self.cameras, self.looks, self.masks = [], [], [], []
        self.displays = {}
        scene = bpy.context.scene
        self.settings = spec["settings"]
        self.width, self.height = spec["size"]
        self.near = min(c["near"] for c in spec["cameras"]) if spec["cameras"] else 0.0
        verts = array(blob, spec["verts"], "<f4", (-1, 3))
        faces = array(blob, spec["faces"], "<u4", (-1, 3))
        pixels = blob[spec["pixels"]["offset"] : spec["pixels"]["offset"] + spec["pixels"]["len"]]
        for t in spec["textures"]:
            self.displays[t["id"]] = self.image(t, pixels)
        meshes = [self.mesh_data(f"mesh{i}", m, verts, faces) for i, m in enumerate(spec["meshes"])]
        materials = {}
        for g, geom in enumerate(spec["geoms"]):
            data = self.shape(g, geom, meshes)
            obj = bpy.data.objects.new(f"geom{g}", data)
            scene.collection.objects.link(obj)
            key = (geom["finish"], tuple(round(c, 4) for c in geom["rgba"]), geom.get("texture"))
            if key not in materials:
                materials[key] = self.material(geom)
                clip_near(materials[key], self.near)
            obj.data.materials.clear()
            obj.data.materials.append(None)
            obj.material_slots[0].link = "OBJECT"
            obj.material_slots[0].material = materials[key]
            self.objects.append(obj)
            self.looks.append(materials[key])
        palette = {}
        for g, geom in enumerate(spec["geoms"]):
            c = tuple(geom["mask"])
            if c not in palette:
                m = bpy.data.materials.new(f"mask{len(palette)}")
                m.use_nodes = True
                nodes = m.node_tree.nodes
                nodes.clear()
                em = nodes.new("ShaderNodeEmission")
                em.inputs["Color"].default_value = (*[srgb_to_linear(x / 255.0) for x in c], 1.0)
                em.inputs["Strength"].default_value = 1.0
                out = nodes.new("ShaderNodeOutputMaterial")
                m.node_tree.links.new(em.outputs[0], out.inputs[0])
                clip_near(m, self.near)
                palette[c] = m
            self.masks.append(palette[c])
        for i, cam in enumerate(spec["cameras"]):
            data = bpy.data.cameras.new(f"camera{i}")
            data.sensor_fit = "VERTICAL"
            data.angle_y = math.radians(cam["fovy_deg"])
            # Clipped by the materials instead (clip_near): Blender's clip runs along the ray.
            data.clip_start = min(cam["near"], 0.001)
            data.clip_end = cam["far"]
            obj = bpy.data.objects.new(f"camera{i}", data)
            scene.collection.objects.link(obj)
            self.cameras.append(obj)
        self.lights = []
        for i, light in enumerate(spec["lights"]):
            if light["directional"]:
                data = bpy.data.lights.new(f"light{i}", "SUN")
                data.energy = 2.5 * light["intensity"]
                data.angle = math.radians(8.0)
            else:
                data = bpy.data.lights.new(f"light{i}", "AREA")
                data.shape = "DISK"
                data.size = 0.8
                data.energy = 260.0 * light["intensity"]
            data.color = light["color"]
            obj = bpy.data.objects.new(f"light{i}", data)
            scene.collection.objects.link(obj)
            self.lights.append(obj)
        # A soft panel over the bench, as a lab's ceiling fixture.
        panel = bpy.data.lights.new("panel", "AREA")
        panel.shape = "RECTANGLE"
        panel.size, panel.size_y = 1.6, 0.8
        panel.energy = 80.0
        obj = bpy.data.objects.new("panel", panel)
        obj.location = (0.0, -0.2, 2.4)
        scene.collection.objects.link(obj)
        self.fixtures = [obj]
        self.world()
        render = scene.render
        render.resolution_x, render.resolution_y = self.width, self.height
        render.resolution_percentage = 100
        render.image_settings.file_format = "PNG"
        render.image_settings.color_mode = "RGB"
        render.image_settings.color_depth = "8"
        render.image_settings.compression = 15
        render.dither_intensity = 0.0
        render.threads_mode = "FIXED"
        render.threads = max(1, int(self.settings["threads"]))
        # Keep the built scene between frames: only moved objects are updated.
        render.use_persistent_data = True
        self.photo()
        self.built = True

    def image(self, t, pixels):
        img = bpy.data.images.new(f"display{t['id']}", t["width"], t["height"], alpha=False)
        self.fill(img, t, pixels)
        return img

    def fill(self, img, t, pixels):
        w, h = t["width"], t["height"]
        rgb = np.frombuffer(pixels[t["offset"] : t["offset"] + w * h * 3], dtype=np.uint8)
        rgba = np.ones((h, w, 4), dtype=np.float32)
        # The display is drawn top row first; Blender's pixel rows run from the bottom.
        rgba[:, :, :3] = np.flipud(rgb.reshape(h, w, 3)) / 255.0
        img.pixels.foreach_set(rgba.ravel())
        img.update()

    def mesh_data(self, name, m, verts, faces):
        mesh = bpy.data.meshes.new(name)
        v = verts[m["vert"] : m["vert"] + m["nvert"]]
        f = faces[m["face"] : m["face"] + m["nface"]]
        mesh.from_pydata(v.tolist(), [], f.tolist())
        mesh.update()
        mesh.shade_smooth()
        mesh.set_sharp_from_angle(angle=math.radians(35))
        return mesh

    def shape(self, g, geom, meshes):
        kind, size = geom["kind"], geom["size"]
        if kind == "mesh":
            return meshes[geom["mesh"]]
        bm = bmesh.new()
        if kind == "box":
            bmesh.ops.create_cube(bm, size=2.0)
            bmesh.ops.scale(bm, vec=size, verts=bm.verts)
        elif kind == "plane":
            sx = size[0] if size[0] > 0 else 5.0
            sy = size[1] if size[1] > 0 else 5.0
            bmesh.ops.create_grid(bm, x_segments=1, y_segments=1, size=1.0)
            bmesh.ops.scale(bm, vec=(sx, sy, 1.0), verts=bm.verts)
        elif kind in ("sphere", "ellipsoid"):
            bmesh.ops.create_uvsphere(bm, u_segments=48, v_segments=24, radius=1.0)
            radii = (size[0],) * 3 if kind == "sphere" else size
            bmesh.ops.scale(bm, vec=radii, verts=bm.verts)
        elif kind in ("cylinder", "capsule"):
            r, hz = size[0], size[1]
            bmesh.ops.create_cone(
                bm, cap_ends=True, segments=64, radius1=r, radius2=r, depth=2.0 * hz
            )
            if kind == "capsule":
                for z in (-hz, hz):
                    ball = bmesh.ops.create_uvsphere(bm, u_segments=32, v_segments=16, radius=r)
                    bmesh.ops.translate(bm, vec=(0.0, 0.0, z), verts=ball["verts"])
        else:
            raise ValueError(f"geom {g}: no shape for `{kind}`")
        mesh = bpy.data.meshes.new(f"shape{g}")
        bm.to_mesh(mesh)
        bm.free()
        if kind in ("sphere", "ellipsoid", "cylinder", "capsule"):
            mesh.shade_smooth()
            mesh.set_sharp_from_angle(angle=math.radians(50))
        return mesh

    def material(self, geom):
        finish = geom["finish"]
        r, g, b, a = geom["rgba"]
        base = (srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b), 1.0)
        m = bpy.data.materials.new(finish)
        m.use_nodes = True
        nodes = m.node_tree.nodes
        bsdf = nodes.get("Principled BSDF")
        i = bsdf.inputs
        i["Base Color"].default_value = base
        if finish == "clear":
            i["Transmission Weight"].default_value = 1.0
            i["Roughness"].default_value = 0.04
            i["IOR"].default_value = 1.49
            # Clear plastic: keep its tint faint.
            i["Base Color"].default_value = tuple(0.2 + 0.8 * c for c in base[:3]) + (1.0,)
        elif finish == "liquid":
            i["Transmission Weight"].default_value = 0.85
            i["Roughness"].default_value = 0.02
            i["IOR"].default_value = 1.333
        elif finish == "display":
            tex = nodes.new("ShaderNodeTexImage")
            tex.image = self.displays[geom["texture"]]
            tex.interpolation = "Closest"
            coords = nodes.new("ShaderNodeTexCoord")
            m.node_tree.links.new(coords.outputs["Generated"], tex.inputs["Vector"])
            m.node_tree.links.new(tex.outputs["Color"], i["Emission Color"])
            i["Emission Strength"].default_value = 1.6
            i["Base Color"].default_value = (0.01, 0.01, 0.01, 1.0)
            i["Roughness"].default_value = 0.15
        elif finish == "metal":
            i["Metallic"].default_value = 1.0
            i["Roughness"].default_value = 0.32
            i["Anisotropic"].default_value = 0.6
        elif finish == "rubber":
            i["Roughness"].default_value = 0.85
            i["Specular IOR Level"].default_value = 0.25
        elif finish == "painted":
            i["Roughness"].default_value = 0.38
            i["Coat Weight"].default_value = 0.1
        elif finish == "bench":
            noise = nodes.new("ShaderNodeTexNoise")
            noise.inputs["Scale"].default_value = 60.0
            mix = nodes.new("ShaderNodeMix")
            mix.data_type = "RGBA"
            mix.inputs["Factor"].default_value = 0.12
            mix.inputs["A"].default_value = base
            m.node_tree.links.new(noise.outputs["Color"], mix.inputs["B"])
            m.node_tree.links.new(mix.outputs["Result"], i["Base Color"])
            i["Roughness"].default_value = 0.55
        else:  # plastic
            i["Roughness"].default_value = 0.45
        return m

    def world(self):
        """An HDR-like room: a bright ceiling, pale walls and a darker floor, lighting everything."""
        world = bpy.data.worlds.new("room")
        bpy.context.scene.world = world
        world.use_nodes = True
        nodes = world.node_tree.nodes
        links = world.node_tree.links
        bg = nodes.get("Background")
        coords = nodes.new("ShaderNodeTexCoord")
        split = nodes.new("ShaderNodeSeparateXYZ")
        ramp = nodes.new("ShaderNodeValToRGB")
        ramp.color_ramp.elements[0].position = 0.35
        ramp.color_ramp.elements[0].color = (0.16, 0.15, 0.14, 1.0)
        ramp.color_ramp.elements[1].position = 0.75
        ramp.color_ramp.elements[1].color = (1.0, 0.98, 0.95, 1.0)
        mid = ramp.color_ramp.elements.new(0.52)
        mid.color = (0.55, 0.57, 0.6, 1.0)
        to01 = nodes.new("ShaderNodeMapRange")
        to01.inputs["From Min"].default_value = -1.0
        to01.inputs["From Max"].default_value = 1.0
        links.new(coords.outputs["Generated"], split.inputs[0])
        # A world's generated coordinate is the view direction: its z is how far up one looks.
        links.new(split.outputs["Z"], to01.inputs["Value"])
        links.new(to01.outputs["Result"], ramp.inputs["Fac"])
        links.new(ramp.outputs["Color"], bg.inputs["Color"])
        bg.inputs["Strength"].default_value = 0.35
        self.world_photo = world
        black = bpy.data.worlds.new("black")
        black.use_nodes = True
        black.node_tree.nodes.get("Background").inputs["Color"].default_value = (0, 0, 0, 1)
        self.world_mask = black

    def photo(self):
        scene = bpy.context.scene
        s = self.settings
        scene.world = self.world_photo
        for obj, mat in zip(self.objects, self.looks):
            obj.material_slots[0].material = mat
        for light in self.lights + self.fixtures:
            light.hide_render = False
        # The rasteriser's colours as given (AgX would wash the paler ones out).
        scene.view_settings.view_transform = "Standard"
        scene.render.filter_size = 1.5
        if s["engine"] == "eevee":
            scene.render.engine = "BLENDER_EEVEE"
            scene.eevee.taa_render_samples = int(s["samples"])
        else:
            scene.render.engine = "CYCLES"
            c = scene.cycles
            c.device = "CPU"
            c.samples = int(s["samples"])
            c.use_adaptive_sampling = False
            c.seed = 0
            c.use_denoising = s["denoiser"] != "none"
            if c.use_denoising:
                c.denoiser = "OPENIMAGEDENOISE"
            c.max_bounces = 8
            c.transmission_bounces = 8
            c.glossy_bounces = 4
            c.diffuse_bounces = 3
        self.mode = "photo"

    def mask(self):
        scene = bpy.context.scene
        scene.world = self.world_mask
        for obj, mat in zip(self.objects, self.masks):
            obj.material_slots[0].material = mat
        for light in self.lights + self.fixtures:
            light.hide_render = True
        scene.view_settings.view_transform = "Standard"
        scene.view_settings.look = "None"
        scene.view_settings.exposure = 0.0
        scene.view_settings.gamma = 1.0
        scene.render.engine = "CYCLES"
        c = scene.cycles
        c.device = "CPU"
        c.samples = 1
        c.use_denoising = False
        c.seed = 0
        # One sample at each pixel's centre: a hard silhouette, as the rasteriser's.
        scene.render.filter_size = 0.01
        self.mode = "mask"

    def frame(self, header, blob):
        if not self.built:
            raise RuntimeError("no scene: the last scene request failed or none was made")
        poses = array(blob, header["geoms"], "<f4", (-1, 12))
        cams = array(blob, header["cameras"], "<f4", (-1, 12))
        if len(poses) != len(self.objects) or len(cams) != len(self.cameras):
            raise ValueError(
                f"{len(poses)} geom and {len(cams)} camera poses for a scene of "
                f"{len(self.objects)} geoms and {len(self.cameras)} cameras"
            )
        for obj, p in zip(self.objects, poses):
            obj.matrix_world = pose_matrix(p)
        for obj, p in zip(self.cameras, cams):
            obj.matrix_world = pose_matrix(p)
        if header["lights"]["len"]:
            lights = array(blob, header["lights"], "<f4", (-1, 6))
            for obj, l in zip(self.lights, lights):
                obj.location = l[:3].tolist()
                # An area light shines along its local -z: its +z points against the light.
                obj.rotation_euler = Vector((-l[3], -l[4], -l[5])).to_track_quat("Z", "Y").to_euler()
        pixels = blob[header["pixels"]["offset"] : header["pixels"]["offset"] + header["pixels"]["len"]]
        for t in header["textures"]:
            self.fill(self.displays[t["id"]], t, pixels)
        want = header.get("mode", "photo")
        if want != self.mode:
            self.photo() if want == "photo" else self.mask()
        scene = bpy.context.scene
        out = bytearray()
        sizes = []
        path = os.path.join(self.tmp, "frame.png")
        for k in header["draw"]:
            scene.camera = self.cameras[k]
            scene.render.filepath = path
            bpy.ops.render.render(write_still=True)
            with open(path, "rb") as f:
                png = f.read()
            sizes.append(len(png))
            out.extend(png)
        return {"ok": True, "sizes": sizes}, bytes(out)


def clip_near(m, near):
    """Surfaces nearer the camera's plane than `near`, and back faces, let rays through: the
    rasteriser's planar near clipping and back-face culling (Blender's clip distance runs along
    each ray, and Blender draws back faces)."""
    nodes, links = m.node_tree.nodes, m.node_tree.links
    out = next(n for n in nodes if n.type == "OUTPUT_MATERIAL")
    shader = out.inputs["Surface"].links[0].from_socket
    depth = nodes.new("ShaderNodeCameraData")
    nearer = nodes.new("ShaderNodeMath")
    nearer.operation = "LESS_THAN"
    nearer.inputs[1].default_value = near
    links.new(depth.outputs["View Z Depth"], nearer.inputs[0])
    # The rasteriser culls back faces: a mesh cut open by the near plane shows what is behind it.
    geometry = nodes.new("ShaderNodeNewGeometry")
    either = nodes.new("ShaderNodeMath")
    either.operation = "MAXIMUM"
    links.new(nearer.outputs["Value"], either.inputs[0])
    links.new(geometry.outputs["Backfacing"], either.inputs[1])
    # For camera rays only: light bouncing and refracting inside the scene sees every face.
    path = nodes.new("ShaderNodeLightPath")
    seen = nodes.new("ShaderNodeMath")
    seen.operation = "MULTIPLY"
    links.new(either.outputs["Value"], seen.inputs[0])
    links.new(path.outputs["Is Camera Ray"], seen.inputs[1])
    through = nodes.new("ShaderNodeBsdfTransparent")
    mix = nodes.new("ShaderNodeMixShader")
    links.new(seen.outputs["Value"], mix.inputs["Fac"])
    links.new(shader, mix.inputs[1])
    links.new(through.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], out.inputs["Surface"])


def pose_matrix(p):
    x, y, z = p[0], p[1], p[2]
    r = p[3:12]
    return Matrix(
        (
            (r[0], r[1], r[2], x),
            (r[3], r[4], r[5], y),
            (r[6], r[7], r[8], z),
            (0.0, 0.0, 0.0, 1.0),
        )
    )


def main():
    stage = Stage()
    answer({"ok": True, "blender": bpy.app.version_string})
    while True:
        header, blob = receive()
        if header is None or header["op"] == "quit":
            shutil.rmtree(stage.tmp, ignore_errors=True)
            return
        try:
            if header["op"] == "scene":
                stage.build(header, blob)
                answer({"ok": True})
            elif header["op"] == "frame":
                h, b = stage.frame(header, blob)
                answer(h, b)
            else:
                answer({"ok": False, "error": f"unknown request `{header['op']}`"})
        except Exception as e:  # noqa: BLE001 - every failure is answered, the worker goes on
            answer({"ok": False, "error": f"{type(e).__name__}: {e}"})


main()
