"""Blender's glTF importer opens a GLB limn baked and finds its material: a Principled BSDF whose
Base Color comes from an image texture of the size baked, and the mesh's UV layer; with
"material", Roughness and Metallic from one non-colour image too, and Normal from a normal map.
Run: blender -b --factory-startup --python-exit-code 2 --python blender_check.py -- FILE.glb SIZE
     [material]
"""
import sys

import bpy
import numpy

numpy.bool = bool  # Debian's numpy 1.24 and Blender 3.4's importer (glTF-Blender-IO #1844)

args = sys.argv[sys.argv.index("--") + 1:]
path, size = args[:2]
material = "material" in args[2:]


def image_upstream(socket):
    """The image texture node feeding a socket, through any nodes between (None if none)."""
    for link in socket.links:
        node = link.from_node
        if node.type == "TEX_IMAGE":
            return node
        for i in node.inputs:
            found = image_upstream(i)
            if found:
                return found
    return None


bpy.ops.wm.read_factory_settings(use_empty=True)
assert bpy.ops.import_scene.gltf(filepath=path, import_shading="SMOOTH") == {"FINISHED"}
meshes = [o for o in bpy.data.objects if o.type == "MESH"]
assert len(meshes) == 1, f"{len(meshes)} mesh objects"
mesh = meshes[0].data
assert len(mesh.uv_layers) == 1, f"{len(mesh.uv_layers)} UV layers"
assert len(mesh.materials) == 1 and mesh.materials[0] is not None, "no material"
tree = mesh.materials[0].node_tree
bsdf = next(n for n in tree.nodes if n.type == "BSDF_PRINCIPLED")
links = bsdf.inputs["Base Color"].links
assert links and links[0].from_node.type == "TEX_IMAGE", "Base Color is not an image texture"
image = links[0].from_node.image
assert tuple(image.size) == (int(size), int(size)), f"image size {tuple(image.size)}"
assert image.colorspace_settings.name == "sRGB", image.colorspace_settings.name
if not material:
    assert not bsdf.inputs["Metallic"].links, "a metallic texture without material channels"
    assert abs(bsdf.inputs["Metallic"].default_value) < 1e-6, "metallic factor is not 0"
    print(f"blender: {path}: material with a {size}x{size} base colour image, UV layer "
          f"{mesh.uv_layers[0].name}, {len(mesh.polygons)} faces")
    sys.exit(0)
mr = [image_upstream(bsdf.inputs[name]) for name in ("Roughness", "Metallic")]
assert mr[0] and mr[1] and mr[0].image == mr[1].image, "roughness and metalness not from one image"
assert mr[0].image.colorspace_settings.name == "Non-Color", mr[0].image.colorspace_settings.name
normal = bsdf.inputs["Normal"].links
assert normal and normal[0].from_node.type == "NORMAL_MAP", "Normal is not from a normal map"
normal_image = image_upstream(bsdf.inputs["Normal"])
assert normal_image and tuple(normal_image.image.size) == (int(size), int(size)), "normal image"
print(f"blender: {path}: material with base colour, metallic-roughness and normal images "
      f"({size}x{size}), UV layer {mesh.uv_layers[0].name}, {len(mesh.polygons)} faces")
