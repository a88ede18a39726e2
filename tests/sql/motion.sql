-- motion.sql — SQL-level specification of the motion_* functions, affect_version and
-- affect_build_info. Run by tests/sql/test_sql.c (see its header for the annotation format);
-- each SELECT without an annotation must give 1 in its second column.

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
    JOINT Head
    {
      OFFSET 0 5 0
      CHANNELS 6 Xposition Yposition Zposition Yrotation Zrotation Xrotation
      End Site
      {
        OFFSET 0 2 0
      }
    }
    JOINT Arm
    {
      OFFSET 3 0 0
      CHANNELS 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.04
1 2 3 0 0 0 0 0 0 0 5 0 0 0 0
1 2 3 90 0 0 90 0 0 0 7 0 0 0 90
0 0 0 0 0 0 90 90 0 0 5 0 0 0 0
', '{"unit":"cm"}'));

-- ---- the registered functions, exactly ----
SELECT group_concat(name || '/' || narg, ' ') FROM (
  SELECT DISTINCT name, narg FROM pragma_function_list
   WHERE name LIKE 'motion\_%' ESCAPE '\' OR name IN ('affect_version', 'affect_build_info')
   ORDER BY name, narg);
-- expect: affect_build_info/0 affect_version/0 motion_bvh_error/1 motion_bvh_error/2 motion_dtw/2 motion_duration/1 motion_fps/1 motion_frames/1 motion_from_bvh/1 motion_from_bvh/2 motion_from_csv/2 motion_from_csv/3 motion_from_json/1 motion_info/1 motion_joints/1 motion_keyframes/1 motion_keyframes/2 motion_kinematics/1 motion_kinematics/2 motion_normalize/1 motion_normalize/2 motion_resample/2 motion_rigid/1 motion_rigid/2 motion_rigid/3 motion_roles/1 motion_roles/2 motion_select/2 motion_slice/3 motion_svg/1 motion_svg/2 motion_svg_group/2 motion_svg_group/3 motion_synth/3 motion_synth/4 motion_to_bvh/1 motion_to_bvh/2 motion_to_csv/1 motion_to_json/1

SELECT 'pure functions are deterministic and innocuous', count(*) = 0 FROM pragma_function_list
 WHERE (name LIKE 'motion\_%' ESCAPE '\' OR name LIKE 'affect\_%' ESCAPE '\')
   AND name NOT IN ('affect_generate', 'affect_generate_explain') -- read a laban index
   AND (flags & 0x000000800) = 0;

SELECT affect_version();
-- expect: 0.1.0

SELECT 'build info', json_extract(affect_build_info(), '$.version') = affect_version()
   AND json_extract(affect_build_info(), '$.libsvm') >= 300
   AND json_extract(affect_build_info(), '$.blas') LIKE '%OpenBLAS%'
   AND json_extract(affect_build_info(), '$.compile_flags') LIKE '%-ffp-contract=off%';

-- ---- motion_from_bvh and the scalars ----
SELECT motion_frames(m) || ' ' || motion_joints(m) || ' ' || motion_fps(m) || ' ' ||
       motion_duration(m) FROM t WHERE name = 'small';
-- expect: 3 5 25.0 0.12

SELECT motion_info(m) FROM t WHERE name = 'small';
-- expect: {"frames":3,"joints":5,"fps":25,"duration":0.12,"unit":"cm","names":["Hips","Chest","Head","Head_end","Arm"],"parents":[-1,0,1,2,1],"bbox":{"min":[-9,0,-1.8369701e-16],"max":[4,19,10]},"skeleton":true,"rotations":true,"bone_variation":0,"bone_variation_joint":"Chest"}

SELECT 'JSON results carry the JSON subtype',
       json_object('info', motion_info(m)) LIKE '{"info":{"frames":3,%' FROM t WHERE name = 'small';

SELECT 'forward kinematics by hand (frame 1, Head_end)',
       group_concat(x || ',' || y || ',' || z) = '-7.0,2.0,10.0'
  FROM motion_points((SELECT m FROM t WHERE name = 'small')) WHERE frame = 1 AND joint = 3;

SELECT 'motion_points has one row per frame and joint', count(*) = 15,
       sum(name = 'Arm') = 3 FROM motion_points((SELECT m FROM t WHERE name = 'small'));

SELECT 'motion_points of NULL is empty', count(*) = 0 FROM motion_points(NULL);

SELECT * FROM motion_points;
-- error: motion_points: a motion argument is required, as in SELECT * FROM motion_points(:motion)

SELECT * FROM motion_points('abc');
-- error: motion_points: the argument must be a motion BLOB, got text

SELECT * FROM motion_points(x'41464d4f');
-- error: motion_points: the argument is not a valid motion: truncated: 4 bytes is shorter than the 32-byte header

SELECT motion_from_bvh('HIERARCHY
ROOT a
{
  OFFSET 0 0 0
  CHANELS 1 Xrotation
}');
-- error: motion_from_bvh: line 5: expected CHANNELS, found CHANELS

SELECT motion_from_bvh(x'00');
-- error: motion_from_bvh: line 1: expected HIERARCHY, found \x00

SELECT motion_from_bvh('HIERARCHY', '{"units":"cm"}');
-- error: motion_from_bvh: unknown option "units" (expected unit, scale, max_samples, on_error)

SELECT motion_from_bvh('HIERARCHY', '{"unit":');
-- error: motion_from_bvh: options (argument 2) are not valid JSON: at byte 8: unexpected end of text

SELECT motion_from_bvh('HIERARCHY', '[1]');
-- error: motion_from_bvh: options (argument 2) must be a JSON object, got array

SELECT motion_from_bvh('HIERARCHY', '{"scale":"big"}');
-- error: motion_from_bvh: option "scale" must be a number, got string

SELECT motion_from_bvh('HIERARCHY', '{"scale":-1}');
-- error: motion_from_bvh: scale must be a positive number, got -1

SELECT motion_from_bvh(NULL) IS NULL;
-- expect: 1

SELECT motion_from_bvh();
-- error: wrong number of arguments to function motion_from_bvh()

-- ---- importing without aborting: {"on_error":"null"} and motion_bvh_error ----
SELECT 'on_error null: a malformed text gives NULL',
       motion_from_bvh('HIERARCHY', '{"on_error":"null"}') IS NULL
   AND motion_from_bvh(x'00', '{"on_error":"null"}') IS NULL
   AND motion_from_bvh('HIERARCHY
ROOT a
{
  OFFSET 0 0 0
  CHANNELS 1 Xrotation
}
MOTION
Frames: 2
Frame Time: 0.1
5
', '{"on_error":"null"}') IS NULL;

SELECT 'on_error null: a good text imports as without it',
       motion_from_bvh(motion_to_bvh(m), '{"on_error":"null","unit":"cm"}') =
       motion_from_bvh(motion_to_bvh(m), '{"unit":"cm"}')
  FROM t WHERE name = 'small';

SELECT 'on_error raise is the default', motion_from_bvh(motion_to_bvh(m), '{"on_error":"raise"}') =
       motion_from_bvh(motion_to_bvh(m)) FROM t WHERE name = 'small';

SELECT motion_from_bvh('HIERARCHY', '{"on_error":"raise"}');
-- error: motion_from_bvh: line 1: expected ROOT, found end of text

SELECT motion_from_bvh('HIERARCHY', '{"on_error":"nul"}');
-- error: motion_from_bvh: option "on_error" must be one of "raise", "null", got "nul"

SELECT motion_from_bvh('HIERARCHY', '{"on_error":"null","scale":-1}');
-- error: motion_from_bvh: scale must be a positive number, got -1

SELECT motion_from_bvh('HIERARCHY', '{"on_error":"null","unit":"c m"}');
-- error: motion_from_bvh: unit has a character other than letters, digits, '_', '.', '-' (byte 1)

SELECT 'motion_bvh_error: NULL when the text imports',
       motion_bvh_error(motion_to_bvh(m)) IS NULL
   AND motion_bvh_error(motion_to_bvh(m), '{"unit":"cm","scale":0.01}') IS NULL
  FROM t WHERE name = 'small';

SELECT motion_bvh_error('HIERARCHY
ROOT a
{
  OFFSET 0 0 0
  CHANELS 1 Xrotation
}');
-- expect: line 5: expected CHANNELS, found CHANELS

SELECT motion_bvh_error('HIERARCHY
ROOT a
{
  OFFSET 0 0 0
  CHANNELS 1 Xrotation
}
MOTION
Frames: 3
Frame Time: 0.1
5
6
');
-- expect: line 12: expected 3 frames, found 2

SELECT motion_bvh_error(x'00');
-- expect: line 1: expected HIERARCHY, found \x00

SELECT motion_bvh_error(x'48495f52ff');
-- expect: line 1: expected HIERARCHY, found HI_R\xff

SELECT 'motion_bvh_error of NULL is NULL', motion_bvh_error(NULL) IS NULL;

SELECT motion_bvh_error('HIERARCHY', '{"on_error":"null"}');
-- error: motion_bvh_error: unknown option "on_error" (expected unit, scale, max_samples)

SELECT motion_bvh_error('HIERARCHY', '{"scale":-1}');
-- error: motion_bvh_error: scale must be a positive number, got -1

SELECT motion_bvh_error('HIERARCHY', '{"unit":"c m"}');
-- error: motion_bvh_error: unit has a character other than letters, digits, '_', '.', '-' (byte 1)

SELECT motion_bvh_error();
-- error: wrong number of arguments to function motion_bvh_error()

-- ---- NULL in, NULL out; wrong types ----
SELECT 'NULL in gives NULL out',
       motion_info(NULL) IS NULL AND motion_frames(NULL) IS NULL AND motion_to_json(NULL) IS NULL
   AND motion_to_csv(NULL) IS NULL AND motion_slice(NULL, 0, 1) IS NULL
   AND motion_slice((SELECT m FROM t), NULL, 1) IS NULL AND motion_resample(NULL, 30) IS NULL
   AND motion_select(NULL, '["a"]') IS NULL AND motion_roles(NULL) IS NULL
   AND motion_normalize(NULL) IS NULL AND motion_svg(NULL) IS NULL
   AND motion_from_json(NULL) IS NULL AND motion_from_csv(NULL, 30) IS NULL
   AND motion_synth(NULL, 'sad', 1) IS NULL AND motion_duration(NULL) IS NULL;

SELECT motion_info('not a blob');
-- error: motion_info: argument 1 must be a motion BLOB, got text

SELECT motion_frames(42);
-- error: motion_frames: argument 1 must be a motion BLOB, got integer

SELECT motion_fps(x'414d464f');
-- error: motion_fps: argument 1 is not a valid motion: truncated: 4 bytes is shorter than the 32-byte header

SELECT motion_joints(zeroblob(40));
-- error: motion_joints: argument 1 is not a valid motion: not a motion (bad magic bytes at offset 0)

SELECT motion_duration(substr(m, 1, length(m) - 1)) FROM t WHERE name = 'small';
-- error: motion_duration: argument 1 is not a valid motion: truncated: 739 bytes, expected 740 for 3 frames x 5 joints

-- ---- JSON and CSV round trips ----
SELECT 'JSON round trip keeps every position (not the rotations: JSON has none)',
       motion_from_json(motion_to_json(m)) = motion_from_json(motion_to_json(motion_from_json(motion_to_json(m))))
   AND motion_to_json(motion_from_json(motion_to_json(m))) = motion_to_json(m) FROM t;

SELECT motion_to_json(motion_slice(m, 0, 0)) FROM t WHERE name = 'small';
-- expect: {"fps":25,"unit":"cm","joints":["Hips","Chest","Head","Head_end","Arm"],"parents":[-1,0,1,2,1],"frames":[[[1,2,3],[1,12,3],[1,17,3],[1,19,3],[4,12,3]]]}

SELECT motion_from_json('{"fps":30,"joints":["a"],"frames":[[[1,2]]]}');
-- error: motion_from_json: frames[0][0]: expected an array of 3 numbers

SELECT motion_from_json('{"fps":30,"joints":["a"],"frames":[[[1,2,3]]]} x');
-- error: motion_from_json: at byte 47: unexpected text after the value

SELECT 'motion_to_csv writes a header and one line per frame', motion_to_csv(motion_slice(m, 1, 1)) =
       'Hips.x,Hips.y,Hips.z,Chest.x,Chest.y,Chest.z,Head.x,Head.y,Head.z,Head_end.x,Head_end.y,' ||
       'Head_end.z,Arm.x,Arm.y,Arm.z' || char(10) || '1,2,3,-9,2,3,-9,2,10,-7,2,10,-9,5,3' || char(10)
  FROM t WHERE name = 'small';

SELECT 'CSV round trip keeps names and positions',
       motion_to_json(motion_from_csv(motion_to_csv(m), 25, '{"unit":"cm"}')) =
       replace(motion_to_json(m), '"parents":[-1,0,1,2,1]', '"parents":[-1,-1,-1,-1,-1]')
  FROM t WHERE name = 'small';

SELECT motion_joints(motion_from_csv('1,2,3,4,5,6
7,8,9,10,11,12', 30)) || ' ' || json_extract(motion_info(motion_from_csv('1,2,3,4,5,6', 30)), '$.names');
-- expect: 2 ["j0","j1"]

SELECT motion_from_csv('a.x,a.y,a.z
1,2,3
4,5', 30);
-- error: motion_from_csv: row 3: expected 3 values, found 2

SELECT motion_from_csv('1,2,3
4,5,x', 30);
-- error: motion_from_csv: row 2, column 3: "x" is not a number

SELECT motion_from_csv('1,2,3', 'fast');
-- error: motion_from_csv: argument 2 must be a finite number, got text

SELECT motion_from_csv('1,2,3', 30, '{"header":"yes"}');
-- error: motion_from_csv: option "header" must be true, false or "auto"

SELECT motion_from_csv('1;2;3', 30, '{"delimiter":";"}') IS NOT NULL;
-- expect: 1

-- ---- editing ----
SELECT motion_frames(motion_slice(m, 1, -1)) || ' ' || motion_frames(motion_resample(m, 50)) ||
       ' ' || motion_joints(motion_select(m, '["Arm","Hips"]'))
  FROM t WHERE name = 'small';
-- expect: 2 5 2

SELECT json_extract(motion_info(motion_select(m, '["Arm","Hips"]')), '$.parents') FROM t WHERE name = 'small';
-- expect: [1,-1]

SELECT motion_slice(m, 2, 1) FROM t WHERE name = 'small';
-- error: motion_slice: last frame 1 is before first frame 2

SELECT motion_slice(m, 'a', 1) FROM t WHERE name = 'small';
-- error: motion_slice: argument 2 must be an integer, got text

SELECT motion_resample(m, 0) FROM t WHERE name = 'small';
-- error: motion_resample: frames per second 0 out of range (0 .. 100000]

SELECT motion_select(m, '["Arm","Tail"]') FROM t WHERE name = 'small';
-- error: motion_select: no joint named "Tail" (selection item 1)

SELECT motion_select(m, '[]') FROM t WHERE name = 'small';
-- error: motion_select: argument 2 must be a non-empty JSON array of joint names

SELECT motion_select(m, '["Arm", 3]') FROM t WHERE name = 'small';
-- error: motion_select: argument 2: item 1 must be a joint name, got number

-- ---- roles and normalization ----
SELECT json_extract(motion_roles(m), '$.pelvis') || ' ' ||
       json_extract(motion_roles(m), '$.chest') || ' ' ||
       ifnull(json_extract(motion_roles(m), '$.left_hand'), 'none') || ' ' ||
       json_extract(motion_roles(m, '{"roles":{"left_hand":"Arm"}}'), '$.left_hand')
  FROM t WHERE name = 'small';
-- expect: Hips Chest none Arm

SELECT motion_roles(m, '{"roles":{"left_hand":"Tail"}}') FROM t WHERE name = 'small';
-- error: motion_roles: option "roles": role left_hand: no joint named "Tail"

SELECT motion_roles(m, '{"roles":{"hand":"Arm"}}') FROM t WHERE name = 'small';
-- error: motion_roles: option "roles": unknown role "hand" (expected pelvis, spine, chest, neck, head, left_/right_ shoulder, elbow, hand, hip, knee, foot, toe)

SELECT motion_roles(m, '{"roles":["Arm"]}') FROM t WHERE name = 'small';
-- error: motion_roles: option "roles" must be an object of role names to joint names, got array

SELECT motion_normalize(m) FROM t WHERE name = 'small';
-- error: motion_normalize: cannot find the heading: the left/right hip and shoulder roles are not resolved (set them with "roles", or "heading": false)

SELECT motion_normalize(m, '{"up":"w"}') FROM t WHERE name = 'small';
-- error: motion_normalize: option "up" must be one of "x", "y", "z", got "w"

SELECT 'normalize without heading moves the pelvis to x = z = 0 and keeps its height',
       json_extract(motion_to_json(motion_normalize(m, '{"heading":false}')), '$.frames[0][0]') = '[0,2,0]'
  FROM t WHERE name = 'small';

SELECT 'normalize with an explicit heading from the hips role pair',
       json_extract(motion_to_json(motion_normalize(m,
         '{"roles":{"left_hip":"Arm","right_hip":"Hips"},"vertical":true}')), '$.frames[0][0]') = '[0,0,0]'
  FROM t WHERE name = 'small';

-- ---- previews ----
SELECT 'motion_svg gives a standalone SVG document',
       motion_svg(m) LIKE '<svg xmlns="http://www.w3.org/2000/svg"%</svg>' || char(10)
  FROM t WHERE name = 'small';

SELECT 'motion_svg options change the drawing and are deterministic',
       motion_svg(m, '{"view":"top","frames":2,"size":64,"title":"a <b>"}') <> motion_svg(m)
   AND motion_svg(m, '{"view":"side"}') = motion_svg(m, '{"view":"side"}')
   AND instr(motion_svg(m, '{"title":"a <b>"}'), 'a &lt;b&gt;') > 0
  FROM t WHERE name = 'small';

SELECT motion_svg(m, '{"frames":0}') FROM t WHERE name = 'small';
-- error: motion_svg: frames must be between 1 and 64, got 0

SELECT motion_svg(m, '{"frames":2.5}') FROM t WHERE name = 'small';
-- error: motion_svg: options "frames", "size" and "keyframes" must be whole numbers

SELECT motion_svg(m, '{"view":"back"}') FROM t WHERE name = 'small';
-- error: motion_svg: option "view" must be one of "front", "side", "top", got "back"

SELECT motion_svg(m, '{"labels":1}') FROM t WHERE name = 'small';
-- error: motion_svg: option "labels" must be true, false, "frame" or "state", got number

-- ---- synthetic movements ----
SELECT 'motion_synth is deterministic for a seed, and seeds are performers',
       motion_synth('wave', 'sad', 3) = motion_synth('wave', 'sad', 3)
   AND motion_synth('wave', 'sad', 3) <> motion_synth('wave', 'sad', 4);

SELECT 'motion_synth: sad lasts longer than neutral, neutral longer than angry',
       motion_duration(motion_synth('knock', 'sad', 1)) > motion_duration(motion_synth('knock', 'neutral', 1))
   AND motion_duration(motion_synth('knock', 'neutral', 1)) > motion_duration(motion_synth('knock', 'angry', 1));

SELECT 'motion_synth honours fps and resolves every role',
       motion_fps(motion_synth('walk', 'happy', 1, '{"fps":60}')) = 60.0
   AND (SELECT count(*) FROM json_each(motion_roles(motion_synth('walk', 'happy', 1))) WHERE value IS NULL) = 0;

SELECT motion_synth('jump', 'sad', 1);
-- error: motion_synth: unknown action "jump" (expected knock, wave, walk, bow)

SELECT motion_synth('wave', 'fear', 1);
-- error: motion_synth: unknown emotion "fear" (expected neutral, happy, sad, angry)

SELECT motion_synth('wave', 'sad', 'x');
-- error: motion_synth: argument 3 must be an integer, got text

SELECT motion_synth('wave', 'sad', 1, '{"intensity":3}');
-- error: motion_synth: intensity must be between 0 and 2, got 3

SELECT motion_synth('wave', 'sad', 1, '{"tempo":2}');
-- error: motion_synth: unknown option "tempo" (expected fps, intensity, noise)

-- ---- sizes from the input (issue 14): "Frames:" against the text left, even without
-- channels; frames × joints against max_samples (AFFECT_MOTION_MAX_SAMPLES = 2^24 by default)
SELECT motion_from_bvh('HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 0
  End Site
  {
    OFFSET 0 10 0
  }
}
MOTION
Frames: 16777216
Frame Time: 0.0083333
');
-- error: motion_from_bvh: line 13: Frames: 16777216 needs more text than the file has left

SELECT motion_from_bvh('HIERARCHY
ROOT j0 {
OFFSET 0 1 0 CHANNELS 0
JOINT j1 {
OFFSET 0 1 0 CHANNELS 0
JOINT j2 {
OFFSET 0 1 0 CHANNELS 0
JOINT j3 {
OFFSET 0 1 0 CHANNELS 0
JOINT j4 {
OFFSET 0 1 0 CHANNELS 0
JOINT j5 {
OFFSET 0 1 0 CHANNELS 0
JOINT j6 {
OFFSET 0 1 0 CHANNELS 0
JOINT j7 {
OFFSET 0 1 0 CHANNELS 0
JOINT j8 {
OFFSET 0 1 0 CHANNELS 0
JOINT j9 {
OFFSET 0 1 0 CHANNELS 0
} } } } } } } } } }
MOTION
Frames: 16777216
Frame Time: 0.0083333
');
-- error: motion_from_bvh: line 25: Frames: 16777216 needs more text than the file has left

SELECT 'without channels a frame is one line end (the last may lack it)',
       motion_frames(motion_from_bvh('HIERARCHY
ROOT a
{
  OFFSET 0 0 0
  CHANNELS 0
}
MOTION
Frames: 3
Frame Time: 0.1


')) = 3;

SELECT motion_from_bvh('HIERARCHY
ROOT a
{
  OFFSET 0 0 0
  CHANNELS 1 Xrotation
  End Site
  {
    OFFSET 0 10 0
  }
}
MOTION
Frames: 3
Frame Time: 0.1
1
2
3
', '{"max_samples":5}');
-- error: motion_from_bvh: line 13: 3 frames x 2 joints is 6 samples, above the limit of 5 (option max_samples)

SELECT 'max_samples sets the limit', motion_frames(motion_from_bvh('HIERARCHY
ROOT a
{
  OFFSET 0 0 0
  CHANNELS 1 Xrotation
  End Site
  {
    OFFSET 0 10 0
  }
}
MOTION
Frames: 3
Frame Time: 0.1
1
2
3
', '{"max_samples":6}')) = 3;

-- 4096 roots without channels and 4097 frames: above the default limit, refused before anything
-- is allocated for the frames; motion_bvh_error reports it, {"on_error":"null"} gives NULL
CREATE TABLE big_bvh AS
WITH RECURSIVE r(i) AS (SELECT 0 UNION ALL SELECT i + 1 FROM r WHERE i < 4095)
SELECT 'HIERARCHY' || char(10) ||
       (SELECT group_concat('ROOT r' || i || char(10) || '{' || char(10) || 'OFFSET 0 0 0' ||
                            char(10) || 'CHANNELS 0' || char(10) || '}', char(10)) FROM r) ||
       char(10) || 'MOTION' || char(10) || 'Frames: 4097' || char(10) || 'Frame Time: 0.01' ||
       replace(hex(zeroblob(4097)), '00', char(10)) AS text;

SELECT motion_from_bvh(text) FROM big_bvh;
-- error: motion_from_bvh: line 20484: 4097 frames x 4096 joints is 16781312 samples, above the limit of 16777216 (option max_samples)
-- oom: skip

SELECT motion_bvh_error(text) FROM big_bvh;
-- expect: line 20484: 4097 frames x 4096 joints is 16781312 samples, above the limit of 16777216 (option max_samples)
-- oom: skip

SELECT 'on_error null: too large gives NULL', motion_from_bvh(text, '{"on_error":"null"}') IS NULL
  FROM big_bvh;
-- oom: skip

SELECT motion_from_bvh('HIERARCHY', '{"max_samples":0}');
-- error: motion_from_bvh: option "max_samples" must be a whole number from 1 to 68719476736, got 0

SELECT motion_from_bvh('HIERARCHY', '{"max_samples":1.5}');
-- error: motion_from_bvh: option "max_samples" must be a whole number from 1 to 68719476736, got 1.5

SELECT motion_from_bvh('HIERARCHY', '{"max_samples":"many"}');
-- error: motion_from_bvh: option "max_samples" must be a number, got string

SELECT motion_from_csv('a.x,a.y,a.z,b.x,b.y,b.z
1,2,3,4,5,6
1,2,3,4,5,6
1,2,3,4,5,6
', 30, '{"max_samples":5}');
-- error: motion_from_csv: row 4: 3 frames x 2 joints is 6 samples, above the limit of 5 (option max_samples)

SELECT 'motion_from_csv: max_samples sets the limit', motion_frames(motion_from_csv('a.x,a.y,a.z,b.x,b.y,b.z
1,2,3,4,5,6
1,2,3,4,5,6
1,2,3,4,5,6
', 30, '{"max_samples":6}')) = 3;

SELECT motion_from_csv('a.x,a.y,a.z', 30, '{"max_samples":-1}');
-- error: motion_from_csv: option "max_samples" must be a whole number from 1 to 68719476736, got -1

-- JSON has no option: its document takes far more memory than the motion
SELECT motion_from_json('{"fps":30,"joints":' ||
       (WITH RECURSIVE r(i) AS (SELECT 0 UNION ALL SELECT i + 1 FROM r WHERE i < 4095)
        SELECT json_group_array('j' || i) FROM r) ||
       ',"frames":[' || substr(replace(hex(zeroblob(4097)), '00', ',[]'), 2) || ']}');
-- error: motion_from_json: frames: 4097 frames x 4096 joints is 16781312 samples, above the limit of 16777216
-- oom: skip

-- resampling: a rate is no size (synthetic motions have 26 joints)
SELECT motion_resample(motion_synth('wave', 'sad', 1), 100000);
-- error: motion_resample: resampling to 100000 fps gives 660001 frames x 26 joints = 17160026 samples, above the limit of 16777216

-- a refused allocation of 16 MiB or more says what it was for and how large, as an error
-- (a bare SQLITE_NOMEM says nothing, and clients such as Python drop its text)
SELECT motion_resample(motion_synth('walk', 'sad', 1), 100000);
-- error: motion_resample: cannot allocate the positions of 613334 frames x 26 joints (182.5 MiB): out of memory
-- heap-limit: 67108864
-- oom: skip
