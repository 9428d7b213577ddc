"""Run by a Python that has ``bpy`` (Blender as a module), never by pytest itself.

    python blender_probe.py MOTION.glb|MOTION.bvh FPS OUT.json

imports the file as Blender's own importers do (glTF with the scene at FPS frames per
second, BVH with the scene's rate taken from the file) and writes, for every frame of
the imported action, the world position of every bone's head and tail, with the
armatures' names, the scene's rate and the frame range.
"""

import json
import sys


def main(path: str, fps: float, out: str) -> None:
    import bpy  # here, so that collecting this file elsewhere does not need Blender

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    if path.lower().endswith(".bvh"):
        bpy.ops.import_anim.bvh(filepath=path, update_scene_fps=True,
                                update_scene_duration=True)
    else:
        scene.render.fps, scene.render.fps_base = round(fps), round(fps) / fps
        bpy.ops.import_scene.gltf(filepath=path)
    arms = [o for o in bpy.data.objects if o.type == "ARMATURE"]
    arm = arms[0]
    action = arm.animation_data.action
    first, last = (round(f) for f in action.frame_range)
    heads, tails = [], []
    for f in range(first, last + 1):
        scene.frame_set(f)
        heads.append([list(arm.matrix_world @ b.head) for b in arm.pose.bones])
        tails.append([list(arm.matrix_world @ b.tail) for b in arm.pose.bones])
    result = {
        "armatures": [a.name for a in arms],
        "bones": [b.name for b in arm.pose.bones],
        "fps": scene.render.fps / scene.render.fps_base,
        "frames": [first, last],
        "heads": heads,
        "tails": tails,
    }
    with open(out, "w", encoding="utf-8") as fh:
        json.dump(result, fh)


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    main(args[0], float(args[1]), args[2])
