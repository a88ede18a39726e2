# blender_bvh.py — imports a BVH file written by motion_to_bvh into headless Blender (the real
# client) and checks the world positions of its joints against expected positions.
#
#   blender -b --factory-startup --python tests/client/blender_bvh.py -- \
#       <bvh file> <expected json file> <tolerance fraction>
#
# The expected JSON is {"frames": [BVH frame indices, 0-based], "joints": {name: [[x, y, z] per
# listed frame]}, "height": body height, and optionally "bones" (the number of ROOT/JOINT
# blocks), "frame_count" and "fps"}, in the BVH file's units and axes. A joint is matched by
# name to a pose bone (its head); a joint named "<parent>_end" is the End Site of <parent>
# (Blender makes no bone for an End Site: it is the tail of the parent's bone). The script exits
# 0 when every joint of every listed frame is within tolerance × height of its expected position
# and the armature, frame count and frame rate are right, 1 otherwise (2 on an error), and
# prints one line (and indented details on failure):
#   blender_bvh: ok|FAIL <file>: <joints> joints x <frames> frames, max error <e> x height ...
#
# How Blender 3.4's importer (io_anim_bvh) maps the file, as found by running it:
#   - axes: with axis_forward='-Z', axis_up='Y' (the defaults: BVH is Y-up, -Z forward) a BVH
#     point (x, y, z) lands at Blender (x, -z, y), so Blender (X, Y, Z) reads back as BVH
#     (X, Z, -Y). The script checks this on the data: when it fails, it prints the signed axis
#     permutation that would fit best.
#   - frames: BVH frame i is Blender frame frame_start + i (frame_start = 1, use_fps_scale off);
#     the importer keeps an internal rest frame 0 that it skips. update_scene_fps sets the
#     scene's frame rate to 1 / Frame Time (checked against "fps").
#   - global_scale = 1: Blender units are the file's units (cm for the corpus, m for ours).
#   - End Sites make no bone: an End Site is the tail of its parent's bone. A joint whose End
#     Site has a zero OFFSET (the corpus walks have them), or a leaf joint without End Site, is a
#     "zero length node": Blender moves its tail 0.1 × global_scale along the file's +Y, so that
#     tail is no longer the End Site; the script then places the End Site rigidly in the bone's
#     frame instead, and names those bones in its summary.
import builtins
import math
import os
import sys
import traceback

import addon_utils
import bpy
from mathutils import Vector

# Blender 3.4's BVH importer (Debian 12's blender) opens files with open(path, 'rU'); the 'U'
# mode was removed in Python 3.11, which Debian's Blender uses, so the import fails with
# "ValueError: invalid mode: 'rU'". Universal newlines are the default of text mode anyway:
# drop the 'U' (Blender ≥ 3.5 opens with 'r').
_builtin_open = builtins.open


def _open_without_u(file, mode="r", *args, **kwargs):
    if isinstance(mode, str) and "U" in mode:
        mode = mode.replace("U", "") or "r"
    return _builtin_open(file, mode, *args, **kwargs)


builtins.open = _open_without_u

FRAME_START = 1
# Blender (X, Y, Z) -> BVH coordinates with axis_forward='-Z', axis_up='Y'.
AXIS_FORWARD, AXIS_UP = "-Z", "Y"


def to_bvh(v):
    return (v[0], v[2], -v[1])


def bvh_to_blender(v):
    return Vector((v[0], -v[2], v[1]))


def parse_hierarchy(path):
    """The ROOT/JOINT names (Blender's spelling: spaces joined by '_') with their parents, the
    End Site offsets by parent name, and the frame count."""
    with _builtin_open(path, "r") as f:
        words_by_line = [line.split() for line in f]
    joints, parents, end_sites, stack, frames = [], {}, {}, [], None
    i = 0
    while i < len(words_by_line):
        w = words_by_line[i]
        if not w:
            i += 1
            continue
        head = w[0].upper()
        if head in ("ROOT", "JOINT"):
            name = "_".join(w[1:])
            parents[name] = stack[-1] if stack else None
            joints.append(name)
            stack.append(name)
        elif head == "END":
            off = words_by_line[i + 2]
            end_sites[stack[-1]] = Vector([float(x) for x in off[1:4]])
            stack.append(None)
        elif head == "}":
            stack.pop()
        elif head == "FRAMES:":
            frames = int(w[1])
        elif head == "MOTION" and not stack:
            pass
        if head == "FRAME" and len(w) > 1 and w[1].upper() == "TIME:":
            break
        i += 1
    return joints, parents, end_sites, frames


def signed_permutations():
    import itertools
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1, -1), repeat=3):
            yield perm, signs


def best_axis_mapping(pairs):
    """The signed axis permutation Blender -> BVH that fits the (blender, expected) pairs best."""
    best = None
    for perm, signs in signed_permutations():
        err = 0.0
        for b, e in pairs:
            m = [signs[k] * b[perm[k]] for k in range(3)]
            err = max(err, math.dist(m, e))
        if best is None or err < best[0]:
            best = (err, perm, signs)
    err, perm, signs = best
    axes = "XYZ"
    text = "(" + ", ".join(("-" if signs[k] < 0 else "") + axes[perm[k]] for k in range(3)) + ")"
    return text, err


def main(argv):
    if len(argv) != 3:
        print("usage: blender -b --factory-startup --python blender_bvh.py -- "
              "<bvh file> <expected json file> <tolerance fraction>")
        return 2
    bvh_path, expected_path, tol = os.path.abspath(argv[0]), argv[1], float(argv[2])
    import json
    with _builtin_open(expected_path, "r") as f:
        expected = json.load(f)
    height = float(expected["height"])
    frames = [int(x) for x in expected["frames"]]
    joints, parents, end_sites, n_frames = parse_hierarchy(bvh_path)
    label = os.path.basename(bvh_path)
    problems = []

    addon_utils.enable("io_anim_bvh", default_set=True)
    before = set(bpy.data.objects)
    result = bpy.ops.import_anim.bvh(
        filepath=bvh_path, target="ARMATURE", global_scale=1.0, frame_start=FRAME_START,
        use_fps_scale=False, update_scene_fps=True, update_scene_duration=True,
        rotate_mode="NATIVE", axis_forward=AXIS_FORWARD, axis_up=AXIS_UP)
    if result != {"FINISHED"}:
        print("blender_bvh: FAIL %s: the importer returned %s" % (label, sorted(result)))
        return 1
    new = [o for o in bpy.data.objects if o not in before]
    arms = [o for o in new if o.type == "ARMATURE"]
    if len(arms) != 1:
        print("blender_bvh: FAIL %s: expected one new armature object, got %s"
              % (label, [(o.name, o.type) for o in new]))
        return 1
    arm = arms[0]
    n_bones = len(arm.data.bones)
    want_bones = int(expected.get("bones", len(joints)))
    if n_bones != len(joints) or n_bones != want_bones:
        problems.append("armature has %d bones, the file %d ROOT/JOINT blocks, expected %d"
                        % (n_bones, len(joints), want_bones))
    want_frames = int(expected.get("frame_count", n_frames or 0))
    if n_frames != want_frames:
        problems.append("the file says %s frames, expected %d" % (n_frames, want_frames))
    render = bpy.context.scene.render
    fps = render.fps / render.fps_base
    if "fps" in expected and abs(fps - float(expected["fps"])) > 1e-6 * float(expected["fps"]):
        problems.append("scene frame rate %.9g after the import, expected %g"
                        % (fps, expected["fps"]))
    action = arm.animation_data.action if arm.animation_data else None
    if action is None:
        problems.append("the armature has no action")
    else:
        first, last = action.frame_range
        if n_frames and (round(first) != FRAME_START or round(last) != FRAME_START + n_frames - 1):
            problems.append("action spans frames %g..%g, expected %d..%d"
                            % (first, last, FRAME_START, FRAME_START + n_frames - 1))

    # Which expected joint is read where: a bone head, or the End Site of a bone.
    zero_length, unmatched, where = [], [], {}
    for name in expected["joints"]:
        if name in arm.data.bones:
            where[name] = ("head", name)
        elif name.endswith("_end") and name[:-4] in end_sites and name[:-4] in arm.data.bones:
            bone = arm.data.bones[name[:-4]]
            # The bone's rest tail is the End Site unless Blender lengthened a zero-length bone.
            rest_end = bone.head_local + bvh_to_blender(end_sites[name[:-4]])
            if (bone.tail_local - rest_end).length > 1e-6 * height:
                zero_length.append(name[:-4])
                where[name] = ("end", name[:-4])
            else:
                where[name] = ("tail", name[:-4])
        else:
            unmatched.append(name)
    # Not an error (the heads are still right), but worth a note: Blender makes up their tails.
    leaves = [name for name in joints
              if name not in end_sites and not any(parents.get(c) == name for c in joints)]
    if unmatched:
        problems.append("no bone for joints %s" % ", ".join(unmatched))

    scene = bpy.context.scene
    max_err, worst, pairs = 0.0, None, []
    for fi, frame in enumerate(frames):
        scene.frame_set(FRAME_START + frame)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        ev = arm.evaluated_get(depsgraph)
        mw = ev.matrix_world
        for name, (kind, bone_name) in where.items():
            pb = ev.pose.bones[bone_name]
            if kind == "head":
                p = mw @ pb.head
            elif kind == "tail":
                p = mw @ pb.tail
            else:
                # The End Site rigidly attached to the bone: its rest position in the bone's frame,
                # moved by the posed bone matrix. The OFFSET is in the file's axes, the armature
                # data in Blender's (the importer applied the axis conversion to it).
                bone = ev.data.bones[bone_name]
                rest_end = bone.head_local + bvh_to_blender(end_sites[bone_name])
                p = mw @ (pb.matrix @ (bone.matrix_local.inverted() @ rest_end))
            got = to_bvh(p)
            want = expected["joints"][name][fi]
            err = math.dist(got, want) / height
            if fi == 0:
                pairs.append((tuple(p), tuple(want)))
            if err > max_err:
                max_err, worst = err, (name, frame, got, want)

    ok = max_err <= tol and not problems
    line = ("blender_bvh: %s %s: %d joints x %d frames, %d bones, %d frames at %.6g fps, max error "
            "%.3g x height (tolerance %g, height %g)"
            % ("ok" if ok else "FAIL", label, len(where), len(frames), n_bones, n_frames or 0, fps,
               max_err, tol, height))
    if zero_length:
        line += ("; End Sites placed in the bone frame (zero-length bones): "
                 + ", ".join(zero_length))
    print(line)
    if leaves:
        print("blender_bvh:   note: joints with neither children nor an End Site (Blender gives "
              "them a made-up tail): " + ", ".join(leaves))
    for p in problems:
        print("blender_bvh:   problem: " + p)
    if max_err > tol and worst:
        name, frame, got, want = worst
        print("blender_bvh:   worst: %s at frame %d: Blender %s, expected %s"
              % (name, frame, ["%.6g" % v for v in got], ["%.6g" % v for v in want]))
        text, err = best_axis_mapping(pairs)
        print("blender_bvh:   best fitting axis mapping Blender -> BVH on frame %d: %s "
              "(max distance %.3g x height); the script uses (X, Z, -Y)"
              % (frames[0], text, err / height))
    sys.stdout.flush()
    return 0 if ok else 1


if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    try:
        code = main(argv)
    except Exception:
        traceback.print_exc()
        print("blender_bvh: ERROR %s" % (argv[0] if argv else "(no file)"))
        code = 2
    sys.stdout.flush()
    sys.exit(code)
