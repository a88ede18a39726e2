-- laban.sql — SQL-level specification of the laban_* scalar functions (Laban Effort and
-- Shape, SCIENCE.md §1). Run by tests/sql/test_sql.c; see its header for the annotations.

CREATE TABLE s(action TEXT, emotion TEXT, seed INTEGER, m BLOB);
INSERT INTO s
SELECT a.value, e.value, k.value, motion_synth(a.value, e.value, k.value)
  FROM json_each('["knock","wave","walk","bow"]') AS a,
       json_each('["neutral","happy","sad","angry"]') AS e,
       json_each('[1,2]') AS k;

SELECT group_concat(name || '/' || narg, ' ') FROM (
  SELECT DISTINCT name, narg FROM pragma_function_list
   WHERE name = 'laban' OR (name LIKE 'laban\_%' ESCAPE '\' AND name NOT IN ('laban_plot', 'laban_salient', 'laban_zvector'))
   ORDER BY name, narg);
-- expect: laban/1 laban/2 laban_flow/1 laban_flow/2 laban_flow/3 laban_names/0 laban_shape_directional/2 laban_shape_directional/3 laban_shape_flow/1 laban_shape_flow/2 laban_shape_shaping/1 laban_shape_shaping/2 laban_space/1 laban_space/2 laban_space/3 laban_time/1 laban_time/2 laban_time/3 laban_vector/1 laban_vector/2 laban_weight/1 laban_weight/2 laban_weight/3

SELECT json_array_length(laban_names()) || ' ' || json_extract(laban_names(), '$[0]') || ' ' ||
       json_extract(laban_names(), '$[26]');
-- expect: 27 WeightAll ShapeDirRHand

-- ---- the thesis's ordering on the synthetic corpus: angry Strong and Sudden, sad Light and
--      Sustained, for every action and performer ----
SELECT 'angry > neutral > sad on WeightAll and TimeAll, ' || a.action || ' seed ' || a.seed,
       laban_weight(a.m) > laban_weight(n.m) AND laban_weight(n.m) > laban_weight(d.m)
   AND laban_time(a.m) > laban_time(n.m) AND laban_time(n.m) > laban_time(d.m)
  FROM s AS a JOIN s AS n USING (action, seed) JOIN s AS d USING (action, seed)
 WHERE a.emotion = 'angry' AND n.emotion = 'neutral' AND d.emotion = 'sad';
-- oom: skip

-- ---- the scalar functions agree with laban() and laban_vector() ----
SELECT 'laban() holds the same values as the component functions',
       abs(json_extract(laban(m), '$.WeightAll') - laban_weight(m)) < 1e-9 * laban_weight(m)
   AND abs(json_extract(laban(m), '$.TimeRHand') - laban_time(m, 'right_hand')) < 1e-9 * laban_time(m, 'right_hand')
   AND abs(json_extract(laban(m), '$.FlowHead') - laban_flow(m, 'head')) < 1e-9 * laban_flow(m, 'head')
   AND abs(json_extract(laban(m), '$.ShapeDirLHand') - laban_shape_directional(m, 'left')) < 1e-12
   AND abs(json_extract(laban(m), '$.ShapeFlow') - laban_shape_flow(m)) < 1e-12
   AND abs(json_extract(laban(m), '$.ShapeSagittal') - json_extract(laban_shape_shaping(m), '$.sagittal')) < 1e-12
  FROM s;
-- oom: skip

SELECT 'the same on one motion (this one also runs under fault injection)',
       abs(json_extract(laban(m), '$.WeightAll') - laban_weight(m)) < 1e-9 * laban_weight(m)
   AND abs(json_extract(laban_shape_shaping(m), '$.vertical') - json_extract(laban(m), '$.ShapeVertical')) < 1e-12
  FROM (SELECT motion_slice(m, 0, 40) AS m FROM s WHERE action = 'wave' AND emotion = 'happy' AND seed = 1);

SELECT 'laban_vector is 27 little-endian float32 in laban_names() order',
       length(laban_vector(m)) = 108
   AND hex(substr(laban_vector(m), 1, 4)) = hex(substr(laban_vector(m), 1, 4))
  FROM s LIMIT 1;

SELECT 'JSON results nest', json_type(json_object('l', laban(m)), '$.l') = 'object'
   AND json_type(json_object('s', laban_shape_shaping(m)), '$.s') = 'object'
  FROM s LIMIT 1;

SELECT 'a joint works as a part, and methods differ from the default',
       laban_weight(m, 'Hand_R') = laban_weight(m, 'right_hand')
   AND laban_weight(m, 'all', '{"method":"deceleration"}') <> laban_weight(m)
   AND laban_time(m, 'all', '{"method":"accumulated","per_second":true}') <
       laban_time(m, 'all', '{"method":"accumulated"}')
   AND laban_space(m, 'right_hand', '{"method":"peaks"}') BETWEEN 1 AND 5
   AND laban_space(m) >= 1
   AND laban_shape_flow(m, '{"hull":"box"}') >= laban_shape_flow(m)
  FROM s WHERE action = 'wave' AND emotion = 'sad' AND seed = 1;

SELECT 'a lower cut-off smooths: peak acceleration drops',
       laban_time(m, 'all', '{"cutoff_hz":2}') < laban_time(m)
   AND laban_time(m, 'all', '{"cutoff_hz":100}') > laban_time(m)
  FROM s WHERE action = 'knock' AND emotion = 'angry' AND seed = 1;

-- ---- NULL in, NULL out ----
SELECT 'NULL in gives NULL out',
       laban_weight(NULL) IS NULL AND laban_time(NULL, 'head') IS NULL AND laban_flow(NULL) IS NULL
   AND laban_space(NULL) IS NULL AND laban_shape_directional(NULL, 'left') IS NULL
   AND laban_shape_directional((SELECT m FROM s), NULL) IS NULL
   AND laban_shape_shaping(NULL) IS NULL AND laban_shape_flow(NULL) IS NULL
   AND laban(NULL) IS NULL AND laban_vector(NULL) IS NULL
   AND laban_weight((SELECT m FROM s), NULL) IS NULL;

-- ---- errors ----
SELECT laban_weight('x');
-- error: laban_weight: argument 1 must be a motion BLOB, got text

SELECT laban_weight(m, 'tail') FROM s LIMIT 1;
-- error: laban_weight: "tail" is neither a part (all, torso, head, left_hand, right_hand, left_foot, right_foot) nor a joint of the motion

SELECT laban_time(motion_select(m, '["Hips","Spine","Chest","Head","Hand_R","Foot_L","Foot_R"]')) FROM s LIMIT 1;
-- error: laban_time: no joint has the left_hand role (assign it with {"roles": {…}}, or use {"missing": "null"})

SELECT 'missing null gives NULL for what cannot be computed and values for the rest',
       laban_time(x, 'all', '{"missing":"null"}') IS NULL
   AND laban_time(x, 'right_hand', '{"missing":"null"}') > 0
   AND json_extract(laban(x, '{"missing":"null"}'), '$.WeightLHand') IS NULL
   AND json_extract(laban(x, '{"missing":"null"}'), '$.WeightRHand') > 0
   AND laban_time(x, 'all', '{"roles":{"left_hand":"Hand_R"}}') > 0
  FROM (SELECT motion_select(m, '["Hips","Spine","Chest","Head","Hand_R","Foot_L","Foot_R","UpperLeg_L","UpperLeg_R"]') AS x FROM s LIMIT 1);

SELECT laban_flow(motion_slice(m, 0, 2)) FROM s LIMIT 1;
-- error: laban_flow: the motion has 3 frames; Flow needs at least 4

SELECT laban_flow(motion_slice(m, 0, 2), 'all', '{"missing":"null"}') IS NULL FROM s LIMIT 1;
-- expect: 1

SELECT laban(motion_slice(m, 0, 2)) FROM s LIMIT 1;
-- error: laban: the motion has 3 frames; Weight, Time and Flow need at least 4

SELECT laban_weight(m, 'all', '{"method":"fast"}') FROM s LIMIT 1;
-- error: laban_weight: option "method" must be one of "peak", "deceleration", got "fast"

SELECT laban_time(m, 'all', '{"cutoff_hz":0}') FROM s LIMIT 1;
-- error: laban_time: cutoff_hz must be a positive number, got 0

SELECT laban_flow(m, 'all', '{"method":"peak"}') FROM s LIMIT 1;
-- error: laban_flow: unknown option "method" (expected cutoff_hz, up, roles, missing)

SELECT laban_space(m, 'all', '{"method":"peaks"}') FROM s LIMIT 1;
-- error: laban_space: method "peaks" needs one hand part (left_hand, right_hand or a joint), not "all"

SELECT laban_space(m, 'all', '{"max_ratio":0.5}') FROM s LIMIT 1;
-- error: laban_space: max_ratio must be at least 1, got 0.5

SELECT laban_shape_directional(m, 'middle') FROM s LIMIT 1;
-- error: laban_shape_directional: "middle" is neither a part (all, torso, head, left_hand, right_hand, left_foot, right_foot) nor a joint of the motion

SELECT laban_shape_flow(m, '{"hull":"sphere"}') FROM s LIMIT 1;
-- error: laban_shape_flow: option "hull" must be one of "convex", "box", got "sphere"

SELECT laban_shape_shaping(motion_select(m, '["Hips","Head"]')) FROM s LIMIT 1;
-- error: laban_shape_shaping: no joints have the left_hip/right_hip (or left_shoulder/right_shoulder) roles (the sagittal direction) (assign it with {"roles": {…}}, or use {"missing": "null"})

SELECT laban_vector(m, '{"speed_floor":1}') FROM s LIMIT 1;
-- error: laban_vector: speed_floor must be in [0, 1), got 1

-- ---- motion_kinematics: the recognizer's kinematic summaries ----
SELECT 'motion_kinematics: 21 named numbers; angry knocks move the hands faster than sad ones',
       (SELECT count(*) FROM json_each(motion_kinematics(m))) = 21
   AND json_extract(motion_kinematics(m), '$.duration') = motion_duration(m)
   AND (SELECT avg(json_extract(motion_kinematics(m), '$.right_hand_speed_p90')) FROM s
         WHERE action = 'knock' AND emotion = 'angry')
     > (SELECT avg(json_extract(motion_kinematics(m), '$.right_hand_speed_p90')) FROM s
         WHERE action = 'knock' AND emotion = 'sad')
  FROM s WHERE action = 'knock' AND emotion = 'angry' AND seed = 1;

SELECT motion_kinematics(NULL) IS NULL, motion_kinematics(m, '{"up":"z"}') IS NOT NULL
  FROM s WHERE seed = 1 AND action = 'knock' AND emotion = 'sad';
-- expect: 1

SELECT motion_kinematics(m, '{"cutoff_hz":3}') FROM s WHERE seed = 1 LIMIT 1;
-- error: motion_kinematics: unknown option "cutoff_hz" (expected up)

SELECT motion_kinematics(x'00');
-- error: motion_kinematics: argument 1 is not a valid motion: truncated: 1 bytes is shorter than the 32-byte header
