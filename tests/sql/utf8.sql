-- utf8.sql — names are UTF-8 and error messages are UTF-8 (issue 14, item 6). Run by
-- tests/sql/test_sql.c, which also fails any statement of any spec whose error message is not
-- valid UTF-8 (clients decode messages as UTF-8: Python raised UnicodeDecodeError instead of
-- showing ours). Here, inputs with bytes that are not UTF-8: names are refused where they
-- enter, and what a message quotes of them is escaped as \xNN.

-- a BVH file in Latin-1: ROOT Tête, the ê as the single byte 0xea
SELECT motion_from_bvh(x'4849455241524348590a524f4f542054ea74650a7b0a20204f46465345542030203020300a20204348414e4e454c5320300a7d0a4d4f54494f4e0a4672616d65733a20310a4672616d652054696d653a20302e30340a0a');
-- error: motion_from_bvh: line 2: joint name is not valid UTF-8 (byte 0xea at offset 1)

SELECT motion_bvh_error(x'4849455241524348590a524f4f542054ea74650a7b0a20204f46465345542030203020300a20204348414e4e454c5320300a7d0a4d4f54494f4e0a4672616d65733a20310a4672616d652054696d653a20302e30340a0a');
-- expect: line 2: joint name is not valid UTF-8 (byte 0xea at offset 1)

-- the same name in UTF-8 is a name like any other
SELECT 'UTF-8 names are kept', json_extract(motion_info(motion_from_bvh('HIERARCHY
ROOT Tête
{
  OFFSET 0 0 0
  CHANNELS 0
}
MOTION
Frames: 1
Frame Time: 0.04

')), '$.names[0]') = 'Tête';

-- a message that quotes the input quotes its bytes escaped
SELECT motion_from_bvh(x'ff0a');
-- error: motion_from_bvh: line 1: expected HIERARCHY, found \xff

SELECT motion_bvh_error(x'c3');
-- expect: line 1: expected HIERARCHY, found \xc3

SELECT motion_synth(CAST(x'6a756dff' AS TEXT), 'sad', 1);
-- error: motion_synth: unknown action "jum\xff" (expected knock, wave, walk, bow)

-- a CSV header in Latin-1
SELECT motion_from_csv(x'54ea74652e782c54ea74652e792c54ea74652e7a0a312c322c330a', 30);
-- error: motion_from_csv: row 1, column 1: the joint name is not valid UTF-8 (byte 0xea at offset 1)

-- a motion BLOB whose joint name is the byte 0xff: every function and table refuses it
SELECT 'the same BLOB with the name "a" is valid',
       motion_joints(x'41464d4f0100000001000000010000000000000000003e400000000000000000010061ffffffff000000000000000000000000') = 1;

SELECT motion_info(x'41464d4f0100000001000000010000000000000000003e4000000000000000000100ffffffffff000000000000000000000000');
-- error: motion_info: argument 1 is not a valid motion: joint 0: name is not valid UTF-8 (byte 0xff at offset 0)

SELECT motion_to_json(x'41464d4f0100000001000000010000000000000000003e4000000000000000000100ffffffffff000000000000000000000000');
-- error: motion_to_json: argument 1 is not a valid motion: joint 0: name is not valid UTF-8 (byte 0xff at offset 0)

SELECT * FROM motion_points(x'41464d4f0100000001000000010000000000000000003e4000000000000000000100ffffffffff000000000000000000000000');
-- error: motion_points: the argument is not a valid motion: joint 0: name is not valid UTF-8 (byte 0xff at offset 0)

-- a training label that is not UTF-8 (the classifier BLOB keeps its labels as text)
SELECT affect_train(motion_synth('wave', 'sad', 1), CAST(x'73ff' AS TEXT));
-- error: affect_train: row 1: label is not valid UTF-8 (byte 0xff at offset 1)
