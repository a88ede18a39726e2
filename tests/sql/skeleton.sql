-- skeleton.sql — SQL-level specification of the skeletal-motion functions: motion_to_bvh,
-- motion_rigid, motion_angles, and what the editing functions do with rotations. Run by
-- tests/sql/test_sql.c (see its header for the annotation format); each SELECT without an
-- annotation must give 1 in its second column.

CREATE TABLE t(name TEXT PRIMARY KEY, m BLOB);

INSERT INTO t VALUES('small', motion_from_bvh('HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Chest
  {
    OFFSET 0 10 0
    CHANNELS 3 Xrotation Yrotation Zrotation
    End Site
    {
      OFFSET 0 5 0
    }
  }
  JOINT Leg
  {
    OFFSET 2 -1 0
    CHANNELS 3 Yrotation Xrotation Zrotation
    JOINT Foot
    {
      OFFSET 0 -8 0
      CHANNELS 3 Zrotation Yrotation Xrotation
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.04
1 2 3 0 0 0 0 0 0 0 0 0 0 0 0
1 2.5 3 90 0 0 -30 0 0 0 45 0 10 0 0
0 0 0 0 90 0 0 0 90 90 0 0 0 0 -20
', '{"unit":"cm"}'));

-- a synthetic wave (metres, positions only) and a position-only copy of the small motion
INSERT INTO t SELECT 'synth', motion_synth('wave', 'happy', 3);
INSERT INTO t SELECT 'positions', motion_from_json(motion_to_json(m)) FROM t WHERE name = 'small';

-- ---- motion_to_bvh with stored rotations: the file is the imported one ----
SELECT 'the exported file is the imported one (at 4 decimals: the rotations are stored as float32)',
       motion_to_bvh(m, '{"precision":4}') = 'HIERARCHY
ROOT Hips
{
	OFFSET 0 0 0
	CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
	JOINT Chest
	{
		OFFSET 0 10 0
		CHANNELS 3 Xrotation Yrotation Zrotation
		End Site
		{
			OFFSET 0 5 0
		}
	}
	JOINT Leg
	{
		OFFSET 2 -1 0
		CHANNELS 3 Yrotation Xrotation Zrotation
		JOINT Foot
		{
			OFFSET 0 -8 0
			CHANNELS 3 Zrotation Yrotation Xrotation
		}
	}
}
MOTION
Frames: 3
Frame Time: 0.04
1 2 3 0 0 0 0 0 0 0 0 0 0 0 0
1 2.5 3 90 0 0 -30 0 0 0 45 0 10 0 0
0 0 0 0 90 0 0 0 90 90 0 0 0 0 -20
' FROM t WHERE name = 'small';
-- oom: skip

CREATE TABLE back AS
SELECT name, motion_from_bvh(motion_to_bvh(m), '{"unit":"cm"}') AS m FROM t WHERE name = 'small';

SELECT 're-imported positions equal the original within 1e-4', max(abs(a.x - b.x) + abs(a.y - b.y) + abs(a.z - b.z)) < 1e-4
  FROM motion_points((SELECT m FROM t WHERE name = 'small')) a
  JOIN motion_points((SELECT m FROM back)) b USING (frame, joint);
-- oom: skip

SELECT 'every rotation order gives the same positions', count(*) = 6 * 15 AND max(abs(a.x - b.x) + abs(a.y - b.y) + abs(a.z - b.z)) < 1e-4
  FROM (SELECT column1 AS o FROM (VALUES ('XYZ'), ('XZY'), ('YXZ'), ('YZX'), ('ZXY'), ('ZYX'))) o
  JOIN motion_points((SELECT m FROM t WHERE name = 'small')) a
  JOIN motion_points(motion_from_bvh(motion_to_bvh((SELECT m FROM t WHERE name = 'small'), json_object('order', o.o)))) b
       USING (frame, joint);
-- oom: skip

SELECT 'options: order, frame time, precision, root name',
       motion_to_bvh(m, '{"order":"XYZ","frame_time":0.02,"precision":2,"root":"pelvis"}')
         LIKE 'HIERARCHY
ROOT pelvis
{
	OFFSET 0 0 0
	CHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation
%Frame Time: 0.02
%'
   AND motion_fps(motion_from_bvh(motion_to_bvh(m, '{"frame_time":0.02}'))) = 50
  FROM t WHERE name = 'small';
-- oom: skip

-- ---- position-only motions go through inverse kinematics ----
SELECT 'a position-only motion exports through IK: rotations, a rigid skeleton',
       json_extract(motion_info(m), '$.rotations') = 0
   AND json_extract(motion_info(motion_from_bvh(motion_to_bvh(m))), '$.rotations') = 1
   AND motion_to_bvh(m) LIKE 'HIERARCHY
ROOT Hips
{
	OFFSET 1 2 3
	CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
	JOINT Chest
	{
		OFFSET 0 10 0
		CHANNELS 3 Zrotation Xrotation Yrotation
		End Site
%'
  FROM t WHERE name = 'positions';
-- oom: skip

CREATE TABLE ik AS
SELECT name, motion_rigid(m) AS rigid, motion_from_bvh(motion_to_bvh(m)) AS back FROM t
 WHERE name IN ('positions', 'synth');

SELECT 'IK export re-imports as the rigid projection (within 0.5 % of the height) ' || ik.name,
       max(abs(a.x - b.x) + abs(a.y - b.y) + abs(a.z - b.z)) < 0.005 * (CASE ik.name WHEN 'synth' THEN 1.9 ELSE 15 END)
  FROM ik, motion_points(ik.rigid) a JOIN motion_points(ik.back) b USING (frame, joint)
 GROUP BY ik.name;
-- oom: skip

SELECT 'siblings: rotation channels only, or position channels on sibling groups',
       motion_to_bvh(m, '{"siblings":"rotate"}') NOT LIKE '%JOINT Chest%CHANNELS 6%'
   AND motion_to_bvh(m, '{"siblings":"translate"}') LIKE '%JOINT UpperLeg_L
%CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation%'
  FROM t WHERE name = 'synth';
-- oom: skip

CREATE TABLE sk AS
SELECT s, motion_from_bvh(motion_to_bvh(s)) AS back
  FROM (SELECT motion_rigid(m, '{"model":"skeleton"}') AS s FROM t WHERE name = 'synth');

SELECT 'motion_rigid with model "skeleton": a skeletal motion that BVH reproduces exactly',
       json_extract(motion_info(sk.s), '$.rotations') = 1
   AND max(abs(a.x - b.x) + abs(a.y - b.y) + abs(a.z - b.z)) < 1e-5
  FROM sk, motion_points(sk.s) a JOIN motion_points(sk.back) b USING (frame, joint);
-- oom: skip

SELECT 'the synthetic wave stretches its bones; motion_rigid does not',
       json_extract(motion_info(m), '$.bone_variation') > 0.01
   AND json_extract(motion_info(motion_rigid(m)), '$.bone_variation') < 2e-6
   AND json_extract(motion_info(motion_rigid(m)), '$.skeleton') = 0
  FROM t WHERE name = 'synth';
-- oom: skip

SELECT 'motion_rigid moves positions less than the stretch',
       max(abs(a.x - b.x) + abs(a.y - b.y) + abs(a.z - b.z)) BETWEEN 1e-4 AND 0.05
  FROM motion_points((SELECT m FROM t WHERE name = 'synth')) a
  JOIN motion_points((SELECT motion_rigid(m) FROM t WHERE name = 'synth')) b USING (frame, joint);
-- oom: skip

SELECT 'motion_rigid: lengths from the first frame, or from a reference motion',
       json_extract(motion_info(motion_rigid(m, '{"lengths":"first"}')), '$.bone_variation') < 2e-6
   AND motion_rigid(m, NULL, m) = motion_rigid(m, '{"lengths":"reference"}', m)
   AND motion_rigid(m, '{"sweeps":1}') IS NOT NULL
  FROM t WHERE name = 'synth';
-- oom: skip

-- ---- motion_angles ----
SELECT 'motion_angles: one row per frame and joint, unit quaternions, the joint''s own order',
       count(*) = 3 * 5 AND max(abs(qw * qw + qx * qx + qy * qy + qz * qz - 1)) < 1e-6
   AND group_concat(DISTINCT "order") = 'ZXY,XYZ,YXZ,ZYX'
  FROM motion_angles((SELECT m FROM t WHERE name = 'small'));

SELECT frame || ' ' || name || ' ' || round(rx, 3) || ' ' || round(ry, 3) || ' ' || round(rz, 3)
  FROM motion_angles((SELECT m FROM t WHERE name = 'small')) WHERE frame = 1 AND name = 'Leg';
-- expect: 1 Leg 45.0 0.0 0.0

SELECT 'angular speed: rad/s by central differences (Hips turns 90 degrees in frames 0 .. 1 at 25 fps)',
       abs(speed - (pi() / 2) * 25 / 2) < 1e-4
  FROM motion_angles((SELECT m FROM t WHERE name = 'small')) WHERE frame = 1 AND name = 'Hips';

SELECT 'motion_angles in a chosen order',
       group_concat(DISTINCT "order") = 'XYZ'
  FROM motion_angles((SELECT m FROM t WHERE name = 'small'), '{"order":"XYZ"}');

SELECT 'motion_angles of a position-only motion come from IK',
       count(*) = 3 * 5 AND max(speed) > 0
  FROM motion_angles((SELECT m FROM t WHERE name = 'positions'));
-- oom: skip

SELECT count(*) FROM motion_angles(NULL);
-- expect: 0

SELECT * FROM motion_angles('x');
-- error: motion_angles: the argument must be a motion BLOB, got text

SELECT * FROM motion_angles((SELECT m FROM t WHERE name = 'small'), '{"order":"XXY"}');
-- error: motion_angles: option "order" must be a rotation order such as "ZXY" (three distinct axes of X, Y, Z)

SELECT * FROM motion_angles;
-- error: motion_angles: a motion argument is required, as in SELECT * FROM motion_angles(:motion)

-- ---- editing keeps rotations consistent, or drops them ----
SELECT 'slice, resample and normalize keep the rotations; select drops them',
       json_extract(motion_info(motion_slice(m, 1, 2)), '$.rotations') = 1
   AND json_extract(motion_info(motion_resample(m, 60)), '$.rotations') = 1
   AND json_extract(motion_info(motion_normalize(m, '{"heading":false}')), '$.rotations') = 1
   AND json_extract(motion_info(motion_select(m, '["Hips","Chest"]')), '$.skeleton') = 0
   AND motion_to_bvh(motion_slice(m, 1, 2), '{"rotations":"stored"}') IS NOT NULL
   AND motion_to_bvh(motion_resample(m, 60), '{"rotations":"stored"}') IS NOT NULL
   AND motion_to_bvh(motion_normalize(m, '{"heading":false}'), '{"rotations":"stored"}') IS NOT NULL
  FROM t WHERE name = 'small';
-- oom: skip

SELECT 'resampling by slerp keeps the bones rigid',
       json_extract(motion_info(motion_resample(m, 60)), '$.bone_variation') < 1e-6
  FROM t WHERE name = 'small';
-- oom: skip

SELECT 'a CSV motion with parents given exports through IK',
       motion_to_bvh(motion_from_csv('a.x,a.y,a.z,b.x,b.y,b.z,c.x,c.y,c.z
0,0,0,0,1,0,1,1,0
0,0,0,0,1,0,0,1,1
0,0,0,0,1,0,-1,1,0', 30, '{"parents":[null,"a",1]}')) LIKE 'HIERARCHY
ROOT a
{
	OFFSET 0 0 0
	CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
	JOINT b
	{
		OFFSET 0 1 0
		CHANNELS 3 Zrotation Xrotation Yrotation
		JOINT c
		{
			OFFSET 1 0 0
%Frames: 3
%';

SELECT motion_from_csv('a.x,a.y,a.z,b.x,b.y,b.z
0,0,0,0,1,0', 30, '{"parents":[1,0]}');
-- error: motion_from_csv: option "parents": joint 0: parent indices form a cycle

SELECT motion_from_csv('a.x,a.y,a.z,b.x,b.y,b.z
0,0,0,0,1,0', 30, '{"parents":["z",null]}');
-- error: motion_from_csv: option "parents": item 0 is not a joint index (-1 .. 1), a joint name or null

SELECT motion_from_csv('a.x,a.y,a.z,b.x,b.y,b.z
0,0,0,0,1,0', 30, '{"parents":[-1]}');
-- error: motion_from_csv: option "parents" must be an array of 2 parents (an index, a joint name, or null for a root)

-- ---- errors ----
SELECT motion_to_bvh(motion_from_csv('a.x,a.y,a.z,b.x,b.y,b.z
0,0,0,1,1,1', 30));
-- error: motion_to_bvh: the motion has no skeleton: no joint has a parent (set parents when importing, e.g. "parents" in JSON)

SELECT motion_rigid(motion_from_csv('a.x,a.y,a.z,b.x,b.y,b.z
0,0,0,1,1,1', 30));
-- error: motion_rigid: the motion has no skeleton: no joint has a parent (set parents when importing, e.g. "parents" in JSON)

SELECT motion_from_json('{"fps":30,"joints":["a","b"],"parents":[1,0],"frames":[[[0,0,0],[1,1,1]]]}');
-- error: motion_from_json: joint 0: parent indices form a cycle

SELECT motion_to_bvh(m, '{"rotations":"stored"}') FROM t WHERE name = 'positions';
-- error: motion_to_bvh: the motion has no stored rotations (it was not imported from BVH); use {"rotations":"auto"} or "ik"

SELECT motion_to_bvh(m, '{"precision":0}') FROM t WHERE name = 'small';
-- error: motion_to_bvh: option "precision" must be a whole number from 1 to 9

SELECT motion_to_bvh(m, '{"rest_frame":3}') FROM t WHERE name = 'small';
-- error: motion_to_bvh: option "rest_frame" must be a whole number from 0 to 2

SELECT motion_to_bvh(m, '{"rotations":"maybe"}') FROM t WHERE name = 'small';
-- error: motion_to_bvh: option "rotations" must be one of "auto", "stored", "ik"

SELECT motion_to_bvh(m, '{"free":["Nope"]}') FROM t WHERE name = 'small';
-- error: motion_to_bvh: option "free": item 0 is not a joint name of the motion: "Nope"

SELECT motion_to_bvh(m, '{"frame_time":-1}') FROM t WHERE name = 'small';
-- error: motion_to_bvh: option "frame_time" must be a positive number of seconds (at most 100000 frames per second)

SELECT motion_to_bvh(m, '{"speed":1}') FROM t WHERE name = 'small';
-- error: motion_to_bvh: unknown option "speed" (expected one of: order, frame_time, precision, root, rotations, rest_frame, lengths, free, siblings)

-- "root" before a bad option: its name, which still points into the options, is not freed
-- (a bad free found by tests/fuzz/fuzz_sql_options)
SELECT motion_to_bvh(m, '{"root":"Root","speed":1}') FROM t WHERE name = 'small';
-- error: motion_to_bvh: unknown option "speed" (expected one of: order, frame_time, precision, root, rotations, rest_frame, lengths, free, siblings)

SELECT motion_to_bvh(m, 3) FROM t WHERE name = 'small';
-- error: motion_to_bvh: options (argument 2) must be a JSON object as text, got integer

SELECT motion_to_bvh('x');
-- error: motion_to_bvh: argument 1 must be a motion BLOB, got text

SELECT motion_rigid(m, '{"lengths":"reference"}') FROM t WHERE name = 'synth';
-- error: motion_rigid: "lengths": "reference" needs a reference motion (argument 3)

SELECT motion_rigid(a.m, NULL, b.m) FROM t a, t b WHERE a.name = 'synth' AND b.name = 'small';
-- error: motion_rigid: the reference motion has 5 joints, the motion 26

SELECT motion_rigid(m, '{"sweeps":0}') FROM t WHERE name = 'synth';
-- error: motion_rigid: option "sweeps" must be a whole number from 1 to 100000

SELECT 'NULL in, NULL out', motion_to_bvh(NULL) IS NULL AND motion_rigid(NULL) IS NULL
   AND motion_to_bvh(NULL, '{"order":"XYZ"}') IS NULL;
