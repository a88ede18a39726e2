-- hmm.sql — SQL-level specification of the hidden Markov model functions (SCIENCE.md §2):
-- hmm_train, hmm_loglik, hmm_viterbi, hmm_viterbi_loglik, hmm_info, hmm_postures.
-- Run by tests/sql/test_sql.c; see its header for the annotations. The per-emotion models are
-- trained once by CREATE TABLE … AS (statements that write run once, also in the --oom mode);
-- the table-wide checks are "-- oom: skip"; a small model covers every function under fault
-- injection.

CREATE TABLE s(action TEXT, emotion TEXT, seed INTEGER, m BLOB);
INSERT INTO s
SELECT a.value, e.value, k.value, motion_synth(a.value, e.value, k.value)
  FROM json_each('["knock","wave","bow"]') AS a,
       json_each('["neutral","happy","sad","angry"]') AS e,
       json_each('[1,2,3,4,5,6]') AS k;

-- ---- registration ----
SELECT group_concat(name || '/' || narg || '/' || type, ' ') FROM (
  SELECT DISTINCT name, narg, type FROM pragma_function_list
   WHERE name LIKE 'hmm\_%' ESCAPE '\' ORDER BY name, narg);
-- expect: hmm_info/1/s hmm_loglik/2/s hmm_loglik/3/s hmm_postures/1/s hmm_train/1/a hmm_train/2/a hmm_viterbi/2/s hmm_viterbi_loglik/2/s

SELECT 'hmm_* are deterministic and innocuous', count(*) = 8 FROM pragma_function_list
 WHERE name LIKE 'hmm\_%' ESCAPE '\' AND (flags & 0x000000800) <> 0 AND (flags & 0x000200000) <> 0;

-- ---- one model per emotion on performers 1–4 (three actions each) ----
CREATE TABLE class_models AS
SELECT emotion AS label,
       hmm_train(m, '{"states":5,"mixtures":1,"joints":["right_hand","left_hand","head","chest"],"velocity":true,"max_iter":8}') AS model
  FROM s WHERE seed <= 4 GROUP BY emotion;

CREATE TABLE class_models2 AS
SELECT emotion AS label,
       hmm_train(m, '{"states":5,"mixtures":2,"covariance":"diag","joints":["right_hand","left_hand","head","pelvis"],"velocity":true,"max_iter":6,"seed":7}') AS model
  FROM s WHERE seed <= 4 GROUP BY emotion;

-- ---- maximum-likelihood recognition of the held-out performers 5 and 6, in plain SQL ----
SELECT 'ML recognition of 24 held-out motions: accuracy ' || avg(emotion = label),
       avg(emotion = label) >= 0.95 AND count(*) = 24
  FROM (SELECT t.rowid, t.emotion, c.label, max(hmm_loglik(c.model, t.m))
          FROM s AS t, class_models AS c WHERE t.seed >= 5 GROUP BY t.rowid);
-- oom: skip

SELECT 'the same with 2 diagonal-covariance mixtures: accuracy ' || avg(emotion = label),
       avg(emotion = label) >= 0.95 AND count(*) = 24
  FROM (SELECT t.rowid, t.emotion, c.label, max(hmm_loglik(c.model, t.m))
          FROM s AS t, class_models2 AS c WHERE t.seed >= 5 GROUP BY t.rowid);
-- oom: skip

SELECT label FROM class_models
 ORDER BY hmm_loglik(model, (SELECT m FROM s WHERE action = 'wave' AND emotion = 'sad' AND seed = 5)) DESC
 LIMIT 1;
-- expect: sad

SELECT label FROM class_models
 ORDER BY hmm_loglik(model, (SELECT m FROM s WHERE action = 'knock' AND emotion = 'angry' AND seed = 6), '{"per_frame":true}') DESC
 LIMIT 1;
-- expect: angry

-- ---- determinism: training twice gives the same bytes ----
SELECT 'training twice gives identical BLOBs',
       (SELECT hmm_train(m, '{"states":5,"mixtures":1,"joints":["right_hand","left_hand","head","chest"],"velocity":true,"max_iter":8}')
          FROM s WHERE seed <= 4 AND emotion = 'sad') = model
  FROM class_models WHERE label = 'sad';
-- oom: skip

-- ---- hmm_info ----
WITH t AS MATERIALIZED (SELECT hmm_info(model) AS i FROM class_models WHERE label = 'angry')
SELECT 'hmm_info: configuration and feature definition',
       json_extract(i, '$.config') = json('{"states":5,"mixtures":1,"dim":24,"covariance":"full","topology":"ergodic","max_jump":0,"start":"first","max_iter":8,"tol":0.0001,"reg":0.0001,"seed":1}')
   AND json_extract(i, '$.features') = json('{"joints":["right_hand","left_hand","head","chest"],"skeleton":["Hand_R","Hand_L","Head","Chest"],"parents":[3,3,3,-1],"frame":"first","normalize":true,"scale":"arm","up":"y","velocity":true,"root":false,"fps":30,"unit":"arm","dim":24}')
  FROM t;

WITH t AS MATERIALIZED (SELECT hmm_info(model) AS i FROM class_models WHERE label = 'happy')
SELECT 'hmm_info: training report, start, transitions, weights, durations',
       json_extract(i, '$.training.sequences') = 12
   AND json_extract(i, '$.training.iterations') BETWEEN 1 AND 8
   AND json_array_length(i, '$.training.loglik') = json_extract(i, '$.training.iterations') + 1
   AND json_type(i, '$.training.converged') IN ('true', 'false')
   AND json_extract(i, '$.training.reseeded') >= 0
   AND json_extract(i, '$.start_probabilities') = '[1,0,0,0,0]'
   AND json_array_length(i, '$.transitions') = 5 AND json_array_length(i, '$.transitions[4]') = 5
   AND json_extract(i, '$.weights') = '[[1],[1],[1],[1],[1]]'
   AND json_array_length(i, '$.durations.frames') = 5
   AND abs(json_extract(i, '$.durations.mean_seconds') * 30 - json_extract(i, '$.durations.mean_frames')) < 1e-9
   AND abs(json_extract(i, '$.durations.seconds[2]') * 30 - json_extract(i, '$.durations.frames[2]')) < 1e-9
   AND abs(json_extract(i, '$.durations.frames[1]') - 1 / (1 - json_extract(i, '$.transitions[1][1]'))) < 1e-9
  FROM t;

SELECT 'hmm_info: training frames', json_extract(hmm_info(model), '$.training.frames') =
       (SELECT sum(motion_frames(m)) FROM s WHERE seed <= 4 AND emotion = 'happy')
  FROM class_models WHERE label = 'happy';
-- oom: skip

SELECT 'transition rows and mixture weights sum to 1', max(abs(total - 1)) < 1e-12 FROM (
  SELECT sum(c.value) AS total FROM class_models2, json_each(hmm_info(model), '$.transitions') AS r,
         json_each(r.value) AS c GROUP BY label, r.key
  UNION ALL
  SELECT sum(c.value) FROM class_models2, json_each(hmm_info(model), '$.weights') AS r,
         json_each(r.value) AS c GROUP BY label, r.key);
-- oom: skip

SELECT 'the thesis cue: sad states last longer than angry ones',
       (SELECT json_extract(hmm_info(model), '$.durations.mean_seconds') FROM class_models WHERE label = 'sad') >
       (SELECT json_extract(hmm_info(model), '$.durations.mean_seconds') FROM class_models WHERE label = 'angry');

SELECT 'JSON results nest', json_type(json_object('i', hmm_info(model)), '$.i') = 'object'
   AND json_type(json_object('p', hmm_viterbi(model, motion_slice(s.m, 0, 9))), '$.p') = 'array'
  FROM class_models, s WHERE label = 'sad' AND s.rowid = 1;

-- ---- a small model: every function also under fault injection ----
CREATE TABLE small AS
SELECT hmm_train(motion_slice(m, 0, 29), '{"states":3,"mixtures":1,"joints":["right_hand","head"],"velocity":true,"max_iter":3,"topology":"left-right"}') AS model
  FROM s WHERE action = 'wave' AND emotion = 'happy' AND seed <= 2;
CREATE TABLE probe AS
SELECT seed, motion_slice(m, 0, 29) AS m FROM s WHERE action = 'wave' AND emotion = 'happy' AND seed <= 2;

SELECT 'hmm_train runs under fault injection',
       substr(hmm_train(x, '{"states":2,"mixtures":2,"joints":["right_hand"],"max_iter":2}'), 1, 6) = x'4146484d0100'
  FROM (SELECT motion_slice(m, 0, 14) AS x FROM probe);

SELECT 'the final log-likelihood of the report is the sum over the training motions',
       abs(json_extract(hmm_info(model), '$.training.loglik[#-1]') -
           (SELECT sum(hmm_loglik(model, m)) FROM probe)) < 1e-9 * abs(json_extract(hmm_info(model), '$.training.loglik[#-1]'))
  FROM small;

WITH t AS MATERIALIZED (SELECT hmm_info(model) AS i FROM small)
SELECT 'hmm_info of the left-right model: an absorbing last state lasts forever (null)',
       json_extract(i, '$.config.topology') = 'left-right'
   AND json_extract(i, '$.transitions[2]') = '[0,0,1]'
   AND json_extract(i, '$.transitions[1][0]') = 0
   AND json_type(i, '$.durations.frames[2]') = 'null'
   AND json_type(i, '$.durations.mean_frames') = 'null'
   AND json_extract(i, '$.features.parents') = '[-1,-1]'
  FROM t;

WITH v AS MATERIALIZED (SELECT hmm_viterbi(model, m) AS p, motion_frames(m) AS n
                          FROM small, probe WHERE seed = 1)
SELECT 'hmm_viterbi: one state per frame, from the first state, never backwards (left-right)',
       json_array_length(p) = n AND json_extract(p, '$[0]') = 0
   AND (SELECT max(value) FROM json_each(p)) = 2
   AND (SELECT json_group_array(value) FROM (SELECT value FROM json_each(p) ORDER BY value)) = p
  FROM v;

SELECT 'hmm_viterbi_loglik: the best path is at most the whole likelihood',
       hmm_viterbi_loglik(model, m) <= hmm_loglik(model, m)
   AND hmm_viterbi_loglik(model, m) > hmm_loglik(model, m) - 50
  FROM small, probe;

SELECT 'per_frame divides by the frame count',
       abs(hmm_loglik(model, m, '{"per_frame":true}') * motion_frames(m) - hmm_loglik(model, m)) <
       1e-12 * abs(hmm_loglik(model, m))
   AND hmm_loglik(model, m, '{"per_frame":false}') = hmm_loglik(model, m)
   AND hmm_loglik(model, m, NULL) = hmm_loglik(model, m)
  FROM small, probe WHERE seed = 2;

-- a literal model (1 state, the head joint without normalization, on the probe motions): as a
-- constant argument it is decoded once per statement and kept as auxiliary data
CREATE TABLE lit AS SELECT CAST(x'4146484D010000000100000001000000030000000000000000000000000000002D431CEBE2361A3F2D431CEBE2361A3F'
    || x'0100000000000000000000000000000002000000210000003C0000000000000001000100010000000000000000003E40'
    || x'6D040068656164040048656164FFFFFFFFFA59F5DA58828040000000000000F03F000000000000F03F000000000000F0'
    || x'3F7577777D29A701BF00000040FAA0F83F676666FA97728ABF701329F7B03B1A3FA7B23E191CC3B83EA7EFD776DCCB86'
    || x'3EA7B23E191CC3B83E009123C3EEF15D3F8ADD267AE87732BFA7EFD776DCCB863E8ADD267AE87732BF98EA25EE599628'
    || x'3FA0026D23EC297BFD' AS BLOB) AS model;

SELECT 'a constant model (decoded once, then reused) scores as a per-row one',
       hmm_loglik(CAST(x'4146484D010000000100000001000000030000000000000000000000000000002D431CEBE2361A3F2D431CEBE2361A3F'
               || x'0100000000000000000000000000000002000000210000003C0000000000000001000100010000000000000000003E40'
               || x'6D040068656164040048656164FFFFFFFFFA59F5DA58828040000000000000F03F000000000000F03F000000000000F0'
               || x'3F7577777D29A701BF00000040FAA0F83F676666FA97728ABF701329F7B03B1A3FA7B23E191CC3B83EA7EFD776DCCB86'
               || x'3EA7B23E191CC3B83E009123C3EEF15D3F8ADD267AE87732BFA7EFD776DCCB863E8ADD267AE87732BF98EA25EE599628'
               || x'3FA0026D23EC297BFD' AS BLOB), m) = hmm_loglik((SELECT model FROM lit), m)
   AND hmm_viterbi_loglik(CAST(x'4146484D010000000100000001000000030000000000000000000000000000002D431CEBE2361A3F2D431CEBE2361A3F'
                       || x'0100000000000000000000000000000002000000210000003C0000000000000001000100010000000000000000003E40'
                       || x'6D040068656164040048656164FFFFFFFFFA59F5DA58828040000000000000F03F000000000000F03F000000000000F0'
                       || x'3F7577777D29A701BF00000040FAA0F83F676666FA97728ABF701329F7B03B1A3FA7B23E191CC3B83EA7EFD776DCCB86'
                       || x'3EA7B23E191CC3B83E009123C3EEF15D3F8ADD267AE87732BFA7EFD776DCCB863E8ADD267AE87732BF98EA25EE599628'
                       || x'3FA0026D23EC297BFD' AS BLOB), m) = hmm_viterbi_loglik((SELECT model FROM lit), m)
  FROM probe;

SELECT 'the literal model', json_extract(hmm_info(model), '$.training.sequences') = 2
   AND json_extract(hmm_info(model), '$.features.joints') = '["head"]'
   AND json_extract(hmm_info(model), '$.features.unit') = 'm'
   AND json_extract(hmm_info(model), '$.config.max_iter') = 0
  FROM lit;

WITH t AS MATERIALIZED (SELECT hmm_postures(model) AS p FROM small)
SELECT 'hmm_postures: one frame per state on the training skeleton',
       motion_frames(p) = 3 AND motion_joints(p) = 2
   AND json_extract(motion_info(p), '$.names') = '["Hand_R","Head"]'
   AND json_extract(motion_info(p), '$.unit') = 'arm'
   AND motion_fps(p) = 30
   AND substr(motion_svg(p), 1, 4) = '<svg'
  FROM t;

WITH t AS MATERIALIZED (SELECT hmm_postures(model) AS p FROM class_models2 WHERE label = 'neutral')
SELECT 'hmm_postures of a mixture model: the weighted mean of the mixture means, with parents',
       motion_frames(p) = 5 AND motion_joints(p) = 4
   AND json_extract(motion_info(p), '$.names') = '["Hand_R","Hand_L","Head","Hips"]'
   AND json_extract(motion_info(p), '$.parents') = '[3,3,3,-1]'
  FROM t;

SELECT 'postures of the sad model hang lower than those of the happy model (head height)',
       (SELECT avg(y) FROM class_models, motion_points(hmm_postures(model)) WHERE label = 'sad' AND name = 'Head') <
       (SELECT avg(y) FROM class_models, motion_points(hmm_postures(model)) WHERE label = 'happy' AND name = 'Head');

-- ---- the defaults: every joint, no velocity ----
SELECT 'defaults: all 26 joints, 7 states x 4 mixtures, full, ergodic',
       json_extract(i, '$.config.states') = 7 AND json_extract(i, '$.config.mixtures') = 4
   AND json_extract(i, '$.config.dim') = 78 AND json_array_length(i, '$.features.joints') = 26
   AND json_extract(i, '$.features.velocity') = 0 AND json_extract(i, '$.features.scale') = 'arm'
  FROM (SELECT hmm_info(hmm_train(m, '{"max_iter":1}')) AS i
          FROM (SELECT m FROM s WHERE action = 'bow' AND emotion = 'sad' AND seed <= 2));
-- oom: skip

SELECT 'options: normalize false, scale none, learned start, left-right with max_jump',
       json_extract(i, '$.features.normalize') = 0 AND json_extract(i, '$.features.scale') = 'none'
   AND json_extract(i, '$.features.unit') = 'm' AND json_extract(i, '$.config.start') = 'learn'
   AND json_extract(i, '$.config.max_jump') = 1
   AND json_extract(i, '$.transitions[0][2]') = 0
  FROM (SELECT hmm_info(hmm_train(m, '{"states":3,"mixtures":1,"joints":["Hand_R"],"normalize":false,"scale":"none","start":"learn","topology":"left-right","max_jump":1,"max_iter":2,"up":"y"}')) AS i
          FROM probe);

-- ---- NULLs and empty input ----
SELECT 'NULL in gives NULL out',
       hmm_loglik(NULL, m) IS NULL AND hmm_loglik(model, NULL) IS NULL
   AND hmm_viterbi(NULL, m) IS NULL AND hmm_viterbi(model, NULL) IS NULL
   AND hmm_viterbi_loglik(model, NULL) IS NULL AND hmm_info(NULL) IS NULL
   AND hmm_postures(NULL) IS NULL
  FROM small, probe WHERE seed = 1;

SELECT hmm_train(m) IS NULL FROM s WHERE seed > 100;
-- expect: 1

SELECT 'NULL motions are skipped; only NULLs give NULL',
       (SELECT hmm_train(NULL, '{"states":2}') IS NULL)
   AND (SELECT hmm_train(x, '{"states":2,"mixtures":1,"joints":["head"],"max_iter":1}') IS NOT NULL
          FROM (SELECT NULL AS x UNION ALL SELECT m FROM probe WHERE seed = 1 UNION ALL SELECT NULL));

-- ---- statements stopped early free the aggregate (checked for leaks in the --oom mode) ----
SELECT emotion, length(hmm_train(motion_slice(m, 0, 11), '{"states":2,"mixtures":1,"joints":["head"],"max_iter":1}'))
  FROM s WHERE seed <= 2 AND action = 'wave' GROUP BY emotion LIMIT 1;
-- expect: angry

SELECT hmm_train(m, CASE WHEN seed = 2 THEN '{"states":2}' ELSE '{"states":3}' END) FROM probe;
-- error: hmm_train: options must be the same on every row

-- motions of two units: unscaled observations would be 100 times off, so they are refused, in
-- training and in scoring; scaled by the arm (the default) they are unit-free
CREATE TABLE units AS
SELECT seed, CASE WHEN seed = 2 THEN motion_from_bvh(motion_to_bvh(m), '{"unit":"cm","scale":100}')
                  ELSE m END AS m
  FROM s WHERE action = 'wave' AND emotion = 'sad' AND seed <= 3;
SELECT hmm_train(m, '{"states":2,"scale":"none"}') FROM (SELECT * FROM units ORDER BY seed);
-- error: hmm_train: row 2: the motion is in cm, the observations in m (convert it, or use motions of one unit; {"scale":"arm"} makes observations unit-free)

SELECT hmm_loglik((SELECT hmm_train(m, '{"states":2,"scale":"none"}') FROM units WHERE seed <> 2), m) FROM units WHERE seed = 2;
-- error: hmm_loglik: the motion is in cm, the observations in m (convert it, or use motions of one unit; {"scale":"arm"} makes observations unit-free)

SELECT 'arm-scaled observations are unit-free (the same BVH round trip in m and in cm)',
       abs(hmm_loglik(h, u.m) - hmm_loglik(h, r.m)) < 1e-5 * abs(hmm_loglik(h, r.m))
  FROM (SELECT hmm_train(m, '{"states":2}') AS h FROM units WHERE seed <> 2), units u,
       (SELECT motion_from_bvh(motion_to_bvh(m)) AS m FROM s
         WHERE seed = 2 AND action = 'wave' AND emotion = 'sad') r
 WHERE u.seed = 2;
-- oom: skip

-- ---- errors ----
SELECT hmm_train('x');
-- error: hmm_train: argument 1 must be a motion BLOB, got text

SELECT hmm_train(m, '{"states":0}') FROM probe;
-- error: hmm_train: states must be between 1 and 256

SELECT hmm_train(m, '{"states":2.5}') FROM probe;
-- error: hmm_train: option "states" must be a whole number from 0 to 4294967295, got 2.5

SELECT hmm_train(m, '{"mixtures":65}') FROM probe;
-- error: hmm_train: mixtures must be between 1 and 64

SELECT hmm_train(m, '{"seed":-1}') FROM probe;
-- error: hmm_train: option "seed" must be a whole number from 0 to 9007199254740992, got -1

SELECT hmm_train(m, '{"covariance":"spherical"}') FROM probe;
-- error: hmm_train: option "covariance" must be one of "full", "diag", got "spherical"

SELECT hmm_train(m, '{"topology":"ring"}') FROM probe;
-- error: hmm_train: option "topology" must be one of "ergodic", "left-right", got "ring"

SELECT hmm_train(m, '{"start":"middle"}') FROM probe;
-- error: hmm_train: option "start" must be one of "first", "learn", got "middle"

SELECT hmm_train(m, '{"max_jump":2}') FROM probe;
-- error: hmm_train: max_jump needs the left-right topology

SELECT hmm_train(m, '{"tol":-1}') FROM probe;
-- error: hmm_train: tol must be a finite number, 0 or more

SELECT hmm_train(m, '{"reg":"big"}') FROM probe;
-- error: hmm_train: option "reg" must be a number, got string

SELECT hmm_train(m, '{"velocity":1}') FROM probe;
-- error: hmm_train: option "velocity" must be true or false, got number

SELECT hmm_train(m, '{"scale":"cm"}') FROM probe;
-- error: hmm_train: option "scale" must be one of "arm", "none", got "cm"

SELECT hmm_train(m, '{"up":"w"}') FROM probe;
-- error: hmm_train: option "up" must be one of "x", "y", "z", got "w"

SELECT hmm_train(m, '{"state":3}') FROM probe;
-- error: hmm_train: unknown option "state" (expected states, mixtures, covariance, topology, max_jump, start, joints, normalize, scale, up, velocity, frame, root, max_iter, tol, reg, seed, progress)

SELECT hmm_train(m, '[3]') FROM probe;
-- error: hmm_train: options (argument 2) must be a JSON object, got array

SELECT hmm_train(m, '{"joints":[]}') FROM probe;
-- error: hmm_train: option "joints" must be a non-empty array of joint or role names, got an empty array

SELECT hmm_train(m, '{"joints":"Hips"}') FROM probe;
-- error: hmm_train: option "joints" must be a non-empty array of joint or role names, got string

SELECT hmm_train(m, '{"joints":["Hips",3]}') FROM probe;
-- error: hmm_train: option "joints": entry 2 must be a joint or role name, got number

SELECT hmm_train(m, '{"joints":["Hips","Tail"]}') FROM probe;
-- error: hmm_train: row 1: joint "Tail" of the model is not in the motion

SELECT hmm_train(m, '{"joints":["Hips","pelvis"]}') FROM probe;
-- error: hmm_train: row 1: joints "Hips" and "pelvis" are the same joint "Hips"

SELECT hmm_train(m, '{"joints":["Hips","Hips"]}') FROM probe;
-- error: hmm_train: row 1: joint "Hips" is listed twice

SELECT hmm_train(x, '{"states":5,"joints":["Hips"]}')
  FROM (SELECT m AS x FROM probe WHERE seed = 1 UNION ALL SELECT motion_slice(m, 0, 3) FROM probe WHERE seed = 2);
-- error: hmm_train: row 2: the motion has 4 frames; 5 states need at least 5

SELECT hmm_train(x, '{"states":2,"joints":["Hips"]}')
  FROM (SELECT m AS x FROM probe WHERE seed = 1 UNION ALL SELECT motion_resample(m, 60) FROM probe WHERE seed = 2);
-- error: hmm_train: row 2: the motion has 60 fps, the first one 30 (resample it with motion_resample)

SELECT hmm_train(x, '{"joints":["Hips"]}')
  FROM (SELECT m AS x FROM probe WHERE seed = 1 UNION ALL SELECT motion_select(m, '["Chest","Hand_R"]') FROM probe WHERE seed = 2);
-- error: hmm_train: row 2: joint "Hips" of the model is not in the motion

SELECT hmm_train(motion_select(m, '["Hips","Chest","Hand_R"]')) FROM probe;
-- error: hmm_train: row 1: cannot remove the heading: no left/right hip or shoulder roles resolve in the motion (train with {"normalize": false})

SELECT hmm_loglik('x', m) FROM probe;
-- error: hmm_loglik: argument 1 must be a model BLOB (from hmm_train), got text

SELECT hmm_info(x'00');
-- error: hmm_info: argument 1 is not a valid model: truncated: 1 bytes is shorter than the 80-byte header

SELECT hmm_info(m) FROM probe;
-- error: hmm_info: argument 1 is not a valid model: not a model (bad magic bytes at offset 0)

SELECT hmm_info(CAST(substr(model, 1, 200) || CASE WHEN substr(model, 201, 1) = x'00' THEN x'01' ELSE x'00' END ||
                     substr(model, 202) AS BLOB)) FROM small;
-- error: hmm_info: argument 1 is not a valid model: model checksum mismatch: the BLOB is corrupt

SELECT hmm_postures(substr(model, 1, length(model) - 1)) FROM small;
-- error: hmm_postures: argument 1 is not a valid model: truncated: 4042 bytes, expected 4043 for 3 states x 1 mixtures x 12 dimensions

SELECT hmm_viterbi(model, 42) FROM small;
-- error: hmm_viterbi: argument 2 must be a motion BLOB, got integer

SELECT hmm_loglik(model, motion_select(m, '["Hips","Chest","Head","UpperArm_L","UpperArm_R"]')) FROM small, probe WHERE seed = 1;
-- error: hmm_loglik: no joint of the motion has the right_hand role (used by the model)

SELECT hmm_viterbi_loglik(model, motion_select(m, '["Hips","Chest","Hand_R","Head","UpperLeg_L","UpperLeg_R"]')) FROM class_models2, probe WHERE label = 'sad' AND seed = 1;
-- error: hmm_viterbi_loglik: no joint of the motion has the left_hand role (used by the model)

SELECT hmm_loglik((SELECT hmm_train(m, '{"states":2,"mixtures":1,"joints":["Hand_R"],"max_iter":1}') FROM probe),
                  motion_select(m, '["Hips","UpperArm_L","UpperArm_R","Hand_L"]')) FROM probe WHERE seed = 1;
-- error: hmm_loglik: joint "Hand_R" of the model is not in the motion

SELECT hmm_loglik(model, m, '{"per_frame":1}') FROM small, probe;
-- error: hmm_loglik: option "per_frame" must be true or false, got number

SELECT hmm_loglik(model, m, '{"frames":true}') FROM small, probe;
-- error: hmm_loglik: unknown option "frames" (expected per_frame)
