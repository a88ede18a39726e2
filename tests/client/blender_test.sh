#!/usr/bin/env bash
# blender_test.sh — the BVH files of motion_to_bvh in a real client: headless Blender imports
# them and its joint positions must be the ones our own reader gives back.
#   blender_test.sh BUILD_DIR SHARED_DIR
#
# Cases, each written by the sqlite3 shell with the built module, then checked by
# tests/client/blender_bvh.py (see its header for Blender's axis and frame mapping):
#   stored rotations   corpus BVH -> motion_from_bvh -> motion_to_bvh (bye and walk, cm, 27
#                      joints); affect_generate's results over a laban index of motion_synth
#                      motions (both methods: their outputs are skeletal)
#   inverse kinematics position-only motions: motion_synth and a corpus walk through
#                      motion_from_json(motion_to_json(m))
# Blender must place every joint where our own reader places it: the positions of
# motion_from_bvh(the written BVH), on ten frames per motion (first and last included), within
# AFFECT_BLENDER_TOL (default 1e-4) × body height (the y extent of the motion's bounding box).
# For the IK cases the script also checks how far those positions are from motion_rigid(m) (the
# constant-bone-length projection), over every frame ("ik:" lines): within
# AFFECT_BLENDER_IK_TOL (default 0.005, the issue's 0.5 %) × body height. They are not equal to
# rounding: where a joint's several bone children keep their angles, one rotation places them
# (captured motions: 1e-6 of the height); where they do not (averaged, generated poses),
# siblings "auto" gives those children position channels. These checks count in the closing
# line like the Blender cases.
# Exits 77 (CTest's skip) when blender is not installed; the corpus cases are skipped with a
# message when SHARED_DIR/corpora is absent.
set -uo pipefail
build=$1 shared=${2:-}
here=$(cd "$(dirname "$0")" && pwd)
tol=${AFFECT_BLENDER_TOL:-1e-4}
ik_tol=${AFFECT_BLENDER_IK_TOL:-0.005}

if ! command -v blender >/dev/null 2>&1; then
    echo "SKIP: blender not installed (apt-get install blender)"
    exit 77
fi
shell=$(command -v sqlite3) || { echo "FAIL: no sqlite3 shell"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
corpus=$shared/corpora/bandai-namco-1/data
have_corpus=0
if [ -n "$shared" ] && [ -d "$shared/corpora" ] && [ -f "$corpus/dataset-1_bye_normal_001.bvh" ] &&
   [ -f "$corpus/dataset-1_walk_angry_001.bvh" ]; then
    have_corpus=1
else
    echo "SKIP: no corpus at $corpus:" \
         "the corpus cases (stored rotations, a corpus walk through IK) are not run"
fi

q() { "$shell" -bail -cmd ".load $build/affect" -cmd ".parameter set :dir '$work'" \
        -cmd ".parameter set :corpus '$corpus'" -cmd ".parameter set :have_corpus $have_corpus" \
        "$work/cases.db" "$@"; }

# 1. The cases: the BVH text and the reference motion whose positions Blender must reproduce.
#    Every function call is stored once in a table: motion_points over a function call would
#    recompute the call for each row.
if ! err=$(q 2>&1 >/dev/null <<'SQL'
CREATE TABLE cases(name TEXT PRIMARY KEY, kind TEXT, bvh TEXT, ref BLOB, rigid BLOB,
                    src_rotations INTEGER);

-- stored rotations: the corpus file read in cm (units kept), written back with its rotations
CREATE TEMP TABLE src AS
SELECT 'corpus-' || f.value || '-stored' AS name,
       motion_from_bvh(readfile(:corpus || '/dataset-1_' || f.value || '_001.bvh'),
                       '{"unit":"cm"}') AS m
  FROM json_each('["bye_normal","walk_angry"]') AS f WHERE :have_corpus;
INSERT INTO cases(name, kind, bvh) SELECT name, 'stored', motion_to_bvh(m) FROM src;

-- position-only motions, written through inverse kinematics
CREATE TEMP TABLE pos(name TEXT, m BLOB);
INSERT INTO pos VALUES('synth-wave-happy-3-ik', motion_synth('wave', 'happy', 3));

CREATE TABLE synth(id INTEGER PRIMARY KEY, emotion TEXT, seed INTEGER, motion BLOB);
INSERT INTO synth(emotion, seed, motion)
SELECT e.value, k.value, motion_synth('wave', e.value, k.value)
  FROM json_each('["neutral","sad","angry"]') AS e, json_each('[1,2,3]') AS k;
CREATE VIRTUAL TABLE idx USING laban(content=synth, motion=motion, label=emotion);
-- generated motions are skeletal (rigid, with rotations): written with their own rotations
INSERT INTO cases(name, kind, bvh)
SELECT 'generated-wave-angry-' || m.value, 'stored',
       motion_to_bvh(affect_generate('idx', motion, 'angry', json_object('method', m.value)))
  FROM synth, json_each('["transfer","hmm_nn"]') AS m WHERE emotion = 'neutral' AND seed = 1;

INSERT INTO pos
SELECT 'corpus-walk_angry-positions-ik', motion_from_json(motion_to_json(m))
  FROM src WHERE name = 'corpus-walk_angry-stored';

INSERT INTO cases(name, kind, bvh, rigid, src_rotations)
SELECT name, 'ik', motion_to_bvh(m), motion_rigid(m), json_extract(motion_info(m), '$.rotations')
  FROM pos;

-- What Blender must show: the positions our own reader gives the written file (units kept).
UPDATE cases SET ref = motion_from_bvh(bvh);

-- How far the IK motion is from motion_rigid(m), over every frame (reported, not checked by
-- Blender): a joint with several bone children gets a best-fit rotation, so its children are
-- placed exactly only when their angles keep the rest frame's.
CREATE TEMP TABLE ik_pts AS
SELECT c.name AS motion, p.frame, p.joint, p.name AS joint_name, p.x, p.y, p.z
  FROM cases AS c, motion_points(c.ref) AS p WHERE c.kind = 'ik';
CREATE TEMP TABLE rigid_pts AS
SELECT c.name AS motion, p.frame, p.joint, p.x, p.y, p.z
  FROM cases AS c, motion_points(c.rigid) AS p WHERE c.kind = 'ik';
CREATE INDEX temp.rigid_at ON rigid_pts(motion, frame, joint);
CREATE TABLE ik_fidelity AS
SELECT motion, joint_name, frame, max(d) AS d FROM (
  SELECT a.motion, a.joint_name, a.frame,
         sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) +
              (a.z - b.z) * (a.z - b.z)) AS d
    FROM ik_pts AS a JOIN rigid_pts AS b USING (motion, frame, joint))
 GROUP BY motion;

-- 2. The expected positions: ten frames spread over each motion, first and last included.
CREATE TEMP TABLE info AS
SELECT name, motion_info(ref) AS i, motion_frames(ref) AS n, motion_fps(ref) AS fps FROM cases;
CREATE TEMP TABLE pick AS
SELECT DISTINCT info.name, CAST(round(k.value * (n - 1) / 9.0) AS INTEGER) AS frame
  FROM info, json_each('[0,1,2,3,4,5,6,7,8,9]') AS k;
CREATE TEMP TABLE pts AS
SELECT c.name AS motion, p.frame, p.joint, p.name AS joint_name, p.x, p.y, p.z
  FROM cases AS c, motion_points(c.ref) AS p
  JOIN pick ON pick.name = c.name AND pick.frame = p.frame;

SELECT writefile(:dir || '/' || c.name || '.bvh', c.bvh),
       writefile(:dir || '/' || c.name || '.json', json_object(
         'frames', (SELECT json_group_array(frame)
                      FROM (SELECT frame FROM pick WHERE name = c.name ORDER BY frame)),
         'joints', (SELECT json_group_object(joint_name, json(xyz))
                      FROM (SELECT joint, joint_name, json_group_array(json_array(x, y, z)) AS xyz
                              FROM (SELECT * FROM pts WHERE motion = c.name ORDER BY joint, frame)
                             GROUP BY joint ORDER BY joint)),
         'height', json_extract(info.i, '$.bbox.max[1]') - json_extract(info.i, '$.bbox.min[1]'),
         'frame_count', info.n, 'fps', info.fps,
         -- a bone per joint, except the End Sites: leaves named "<parent>_end"
         'bones', json_array_length(info.i, '$.names') - (
           SELECT count(*)
             FROM json_each(info.i, '$.names') AS j, json_each(info.i, '$.parents') AS p
            WHERE p.key = j.key AND p.value >= 0
              AND j.value = json_extract(info.i, '$.names[' || p.value || ']') || '_end'
              AND NOT EXISTS (SELECT 1 FROM json_each(info.i, '$.parents') AS c2
                               WHERE c2.value = j.key))))
  FROM cases AS c JOIN info USING (name) ORDER BY c.name;
SQL
); then
    echo "FAIL: writing the BVH files and expected positions: $err"
    echo "blender: 0 passed, 1 failed"
    exit 1
fi

with_rotations=$(q "SELECT group_concat(name, ', ') FROM cases WHERE kind = 'ik' AND src_rotations")
if [ -n "$with_rotations" ]; then
    echo "FAIL: these sources should be position-only motions (no rotations): $with_rotations"
    echo "blender: 0 passed, 1 failed"
    exit 1
fi

# The IK motions against motion_rigid(m): a loose bound, only against gross IK regressions.
passed=0 failed=0
while IFS='|' read -r name rel joint frame; do
    if awk -v r="$rel" -v b="$ik_tol" 'BEGIN { exit !(r <= b) }'; then
        verdict=ok passed=$((passed + 1))
    else
        verdict=FAIL failed=$((failed + 1))
    fi
    echo "ik: $verdict $name: the written BVH's positions vs motion_rigid(m): max $rel x height" \
         "($joint, frame $frame; bound $ik_tol)"
done < <(q "SELECT f.motion, printf('%.3g', f.d / (json_extract(c.i, '$.bbox.max[1]') -
                                                   json_extract(c.i, '$.bbox.min[1]'))),
                   f.joint_name, f.frame
              FROM ik_fidelity AS f
              JOIN (SELECT name, motion_info(ref) AS i FROM cases) AS c ON c.name = f.motion
             ORDER BY f.motion")

# 3. Blender on each case.
for bvh in "$work"/*.bvh; do
    name=$(basename "$bvh" .bvh)
    start=$(date +%s%N)
    out=$(timeout 300 blender -b --factory-startup --python "$here/blender_bvh.py" -- \
        "$bvh" "$work/$name.json" "$tol" 2>&1)
    rc=$?
    ms=$((($(date +%s%N) - start) / 1000000))
    echo "$out" | grep '^blender_bvh:'
    # what Blender's importer said about the file: zero-length bones it lengthened, warnings
    zero=$(echo "$out" | grep -oE 'zero length (node|bone) found: *[^ ]+' | sed -E 's/.*: *//' |
        sort -u | paste -sd' ')
    [ -z "$zero" ] || echo "  Blender: zero length node found (tail moved 0.1 along +Y): $zero"
    echo "$out" | grep -v '^blender_bvh:' | grep -iE 'warning|error' | sed 's/^/  Blender: /'
    printf '  (%s: %d.%01d s in Blender)\n' "$name" $((ms / 1000)) $((ms % 1000 / 100))
    if [ "$rc" -eq 0 ]; then
        passed=$((passed + 1))
    else
        failed=$((failed + 1))
        echo "FAIL: $name (exit $rc); Blender's output:"
        echo "$out" | tail -40 | sed 's/^/    /'
    fi
done
echo "blender: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
