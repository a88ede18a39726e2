-- fda.sql — SQL-level specification of the functional analysis of movements (SCIENCE.md §4;
-- thesis chapter 3): fda_train, fda_embed, fda_classify, fda_info, fda_prototype, fda_plot.
-- Run by tests/sql/test_sql.c; see its header for the annotations. The models are made once by
-- CREATE TABLE … AS; the checks over many motions are "-- oom: skip", the small model's
-- functions run under fault injection.

CREATE TABLE fs AS
SELECT e.value AS emotion, k.value AS seed, motion_synth('wave', e.value, k.value) AS m
  FROM json_each('["neutral","happy","sad","angry"]') AS e, json_each('[1,2,3,4,5,6]') AS k;

-- ---- registration ----
SELECT group_concat(name || '/' || narg || '/' || type, ' ') FROM (
  SELECT DISTINCT name, narg, type FROM pragma_function_list
   WHERE name LIKE 'fda\_%' ESCAPE '\' ORDER BY name, narg);
-- expect: fda_classify/2/s fda_classify/3/s fda_embed/2/s fda_info/1/s fda_plot/1/s fda_plot/2/s fda_prototype/2/s fda_train/2/a fda_train/3/a

SELECT 'the functional functions are deterministic and innocuous', count(*) = 9
  FROM pragma_function_list
 WHERE name LIKE 'fda\_%' ESCAPE '\'
   AND (flags & 0x000000800) <> 0 AND (flags & 0x000200000) <> 0;

-- ---- models: FPCA (20 B-splines, 2-D) and one of each other method ----
CREATE TABLE fm AS
SELECT 'fpca' AS method, fda_train(m, emotion, '{"basis":20,"dims":2,"method":"fpca"}') AS model FROM fs
UNION ALL
SELECT 'ffda', fda_train(m, emotion, '{"basis":20,"method":"ffda"}') FROM fs
UNION ALL
SELECT 'fspca', fda_train(m, emotion, '{"basis":20,"method":"fspca","kernel":"rbf","sigma":0.5}') FROM fs
UNION ALL
SELECT 'fisomap', fda_train(m, emotion, '{"basis":20,"method":"fisomap","isomap_k":10}') FROM fs
UNION ALL
SELECT 'small', fda_train(m, emotion, '{"basis":6,"dims":2,"joints":["right_hand"],"frame":"first","method":"fpca"}') FROM fs WHERE seed <= 3;

SELECT 'an AFFD BLOB of version 3 (flags 2: the prototypes are the class means, the default)',
       substr(model, 1, 12) = x'414646440300000002000000' FROM fm;

SELECT 'proto_dims: "all" by default, the thesis''s 3 one option away (version 1, as before)',
       json_extract(fda_info(model), '$.proto_dims') = 'all'
   AND json_extract(fda_info(fda_train(m, emotion, '{"basis":20,"dims":2,"method":"fpca","proto_dims":3}')), '$.proto_dims') = 3
   AND substr(fda_train(m, emotion, '{"basis":20,"dims":2,"method":"fpca","proto_dims":3}'), 1, 12) = x'414646440100000000000000'
   AND fda_train(m, emotion, '{"basis":20,"dims":2,"method":"fpca","proto_dims":"all"}') = model
  FROM fm, fs WHERE method = 'fpca' GROUP BY model;
-- oom: skip

SELECT fda_train(m, emotion, '{"proto_dims":0}') FROM fs;
-- error: fda_train: proto_dims must be from 1 to 64, or all
SELECT fda_train(m, emotion, '{"proto_dims":"some"}') FROM fs;
-- error: fda_train: option "proto_dims" must be a number or "all"

SELECT 'retraining gives the same bytes', model = (SELECT fda_train(m, emotion, '{"basis":20,"dims":2,"method":"fpca"}') FROM fs)
  FROM fm WHERE method = 'fpca';
-- oom: skip

SELECT 'fda_info: method, basis, classes in byte order, dimensions',
       json_extract(fda_info(model), '$.method') = 'fpca'
   AND json_extract(fda_info(model), '$.basis') = 20
   AND json_extract(fda_info(model), '$.order') = 4
   AND json_extract(fda_info(model), '$.lambda') = 1e-10
   AND json_extract(fda_info(model), '$.lambda_from') = 'option'
   AND json_extract(fda_info(model), '$.dims') = 2
   AND json_extract(fda_info(model), '$.motions') = 24
   AND json_extract(fda_info(model), '$.coordinates') = 78
   AND json(json_extract(fda_info(model), '$.classes')) = '["angry","happy","neutral","sad"]'
   AND json_extract(fda_info(model), '$.observations.frame') = 'body'
  FROM fm WHERE method = 'fpca';

SELECT 'fda_info: the training labels and embedding (24 motions x 2)',
       json_array_length(fda_info(model), '$.train_labels') = 24
   AND json_array_length(fda_info(model), '$.train_embedding') = 24
   AND json_array_length(fda_info(model), '$.train_embedding[0]') = 2
  FROM fm WHERE method = 'fpca';

SELECT 'fda_info: eigenvalues decrease, explained shares in (0, 1]',
       json_extract(fda_info(model), '$.eigenvalues[0]') >= json_extract(fda_info(model), '$.eigenvalues[1]')
   AND json_extract(fda_info(model), '$.explained[0]') > 0
   AND json_extract(fda_info(model), '$.explained[0]') + json_extract(fda_info(model), '$.explained[1]') <= 1
  FROM fm WHERE method = 'fpca';

SELECT 'the default method is FFDA (the measured best on both corpora: docs/EVALUATION.md)',
       json_extract(fda_info(fda_train(m, emotion, '{"basis":20}')), '$.method') = 'ffda'
  FROM fs;
-- oom: skip

SELECT 'FFDA and FSPCA keep at most c - 1 = 3 axes, Isomap the 3 asked',
       json_extract(fda_info(model), '$.dims') = 3 FROM fm WHERE method IN ('ffda', 'fspca', 'fisomap');

SELECT 'the small model on the right hand: 3 coordinates, 6 B-splines',
       json_extract(fda_info(model), '$.coordinates') = 3
   AND json_extract(fda_info(model), '$.basis') = 6
  FROM fm WHERE method = 'small';

SELECT 'fda_embed: a float32 vector of the model''s dimensions',
       length(fda_embed(model, m)) = 4 * json_extract(fda_info(model), '$.dims')
  FROM fm, fs WHERE method = 'small' AND seed = 1;

SELECT 'every method classifies its training waves right at least 90 % of the time (1-NN)',
       avg(fda_classify(model, m) = emotion) >= 0.9
  FROM fm, fs WHERE method <> 'small' GROUP BY method;
-- oom: skip

SELECT 'held-out waves (seeds 7, 8) of the FSPCA model: 7 of 8 or better',
       sum(fda_classify(model, motion_synth('wave', e.value, k.value), 3) = e.value) >= 7
  FROM fm, json_each('["neutral","happy","sad","angry"]') AS e, json_each('[7,8]') AS k
 WHERE method = 'fspca';
-- oom: skip

SELECT 'fda_classify on the small model', fda_classify(model, m) IN ('angry', 'happy', 'neutral', 'sad')
  FROM fm, fs WHERE method = 'small' AND seed = 2 AND emotion = 'sad';

-- ---- landmark registration ("alignment":"landmarks") ----
CREATE TABLE flm AS
SELECT fda_train(m, emotion, '{"basis":20,"method":"ffda","alignment":"landmarks"}') AS model,
       fda_train(m, emotion, '{"basis":20,"method":"ffda"}') AS linear FROM fs;

SELECT 'landmarks: flag 1 (version 3 with the default prototypes), the template in fda_info (times increasing in (0, 1), rests and peaks)',
       substr(hex(model), 9, 8) = '03000000' AND substr(hex(model), 17, 8) = '03000000'
   AND substr(hex(linear), 17, 8) = '02000000'
   AND json_extract(fda_info(model), '$.alignment') = 'landmarks'
   AND json_extract(fda_info(linear), '$.alignment') = 'linear'
   AND json_array_length(fda_info(linear), '$.landmarks') = 0
   AND json_array_length(fda_info(model), '$.landmarks') >= 1
   AND NOT EXISTS (SELECT 1 FROM json_each(fda_info(model), '$.landmarks') AS a
                    WHERE json_extract(a.value, '$.t') <= 0 OR json_extract(a.value, '$.t') >= 1
                       OR json_extract(a.value, '$.type') NOT IN ('rest', 'peak')
                       OR (a.key > 0 AND json_extract(a.value, '$.t') <=
                           json_extract(fda_info(model), '$.landmarks[' || (a.key - 1) || '].t')))
  FROM flm;

SELECT 'landmarks: a training wave registered as an unseen one gets its training class (1-NN on the training set)',
       avg(fda_classify(model, m) = emotion) >= 0.9
  FROM flm, fs;
-- oom: skip

SELECT fda_train(m, emotion, '{"alignment":"dtw"}') FROM fs;
-- error: fda_train: option "alignment" must be one of "linear", "landmarks", got "dtw"

SELECT 'affect_crossval takes the alignment too: the same fold as by hand',
       (SELECT accuracy FROM affect_crossval('fs', 'm', 'emotion', '{"group":"seed","methods":["ffda"],"basis":20,"alignment":"landmarks"}') WHERE fold = 1)
     = (SELECT avg(fda_classify((SELECT fda_train(m, emotion, '{"basis":20,"method":"ffda","alignment":"landmarks"}') FROM fs WHERE seed <> 1), m) = emotion)
          FROM fs WHERE seed = 1);
-- oom: skip

CREATE TEMP TABLE fshort AS SELECT emotion, seed, motion_slice(m, 0, 2) AS m FROM fs;
SELECT 'affect_crossval with functional methods only takes motions shorter than the HMM states (3 frames)',
       count(*) = 7 AND min(motion_frames(m)) = 3
  FROM affect_crossval('fshort', 'm', 'emotion', '{"group":"seed","methods":["ffda"],"basis":4}'),
       (SELECT m FROM fshort LIMIT 1);
SELECT * FROM affect_crossval('fshort', 'm', 'emotion', '{"group":"seed","methods":["ffda","svm"],"basis":4}');
-- error: affect_crossval: affect_crossval_json: row 1: the motion has 3 frames; 5 states need at least 5

SELECT 'fda_prototype: the class''s mean length, on the model''s skeleton, exportable',
       motion_frames(fda_prototype(model, 'sad')) = (SELECT round(avg(motion_frames(m))) FROM fs WHERE emotion = 'sad')
   AND motion_joints(fda_prototype(model, 'sad')) = 26
   AND motion_to_bvh(fda_prototype(model, 'sad')) LIKE 'HIERARCHY%'
  FROM fm WHERE method = 'fpca';
-- oom: skip

SELECT 'fda_prototype of the small model', motion_joints(fda_prototype(model, 'angry')) = 1
  FROM fm WHERE method = 'small';

SELECT 'fda_plot: an SVG with one legend entry per class',
       fda_plot(model, '{"title":"waves"}') LIKE '<svg xmlns="http://www.w3.org/2000/svg"%</svg>' || char(10)
   AND instr(fda_plot(model), 'neutral') > 0
  FROM fm WHERE method = 'small';

SELECT 'fda_plot: a perturbation plot of the right hand''s y (the small model''s coordinate 2)',
       fda_plot(model, '{"axis":1,"coordinate":2,"alpha":3}') LIKE '<svg%mean + 3 sd%</svg>' || char(10)
   AND instr(fda_plot(model, '{"axis":1,"coordinate":2}'), 'right_hand y') > 0
  FROM fm WHERE method = 'small';

-- ---- NULL in, NULL out ----
SELECT 'NULL model', fda_embed(NULL, m) IS NULL AND fda_classify(NULL, m) IS NULL
   AND fda_info(NULL) IS NULL AND fda_prototype(NULL, 'sad') IS NULL AND fda_plot(NULL) IS NULL
  FROM fs WHERE seed = 1 AND emotion = 'sad';
SELECT 'NULL motion', fda_embed(model, NULL) IS NULL AND fda_classify(model, NULL) IS NULL
  FROM fm WHERE method = 'small';
SELECT 'no rows, or only NULL motions', (SELECT fda_train(m, emotion) FROM fs WHERE 0) IS NULL
   AND (SELECT fda_train(NULL, emotion) FROM fs) IS NULL;

-- ---- errors ----
SELECT fda_embed('x', m) FROM fs LIMIT 1;
-- error: fda_embed: argument 1 must be a functional model BLOB (from fda_train), got text
SELECT fda_info(x'00');
-- error: fda_info: argument 1 is not a valid functional model: truncated: 1 bytes is shorter than the functional model header
SELECT fda_info(zeroblob(200));
-- error: fda_info: argument 1 is not a valid functional model: not a functional model (bad magic bytes at offset 0)
SELECT fda_info(CAST(substr(model, 1, 150) || x'00' || substr(model, 152) AS BLOB)) FROM fm WHERE method = 'small';
-- error: fda_info: argument 1 is not a valid functional model: functional model checksum mismatch: the BLOB is corrupt
SELECT fda_train(m, emotion, '{"method":"x"}') FROM fs;
-- error: fda_train: option "method" must be one of "fpca", "ffda", "fspca", "fisomap", got "x"
SELECT fda_train(m, emotion, '{"lambda":"x"}') FROM fs;
-- error: fda_train: option "lambda" must be a number or "gcv"
SELECT fda_train(m, emotion, '{"dims":0}') FROM fs;
-- error: fda_train: dims must be from 1 to 64
SELECT fda_train(m, emotion, '{"basis":3}') FROM fs;
-- error: fda_train: the basis size must be from the order to 4096
SELECT fda_train(m, emotion, '{"states":3}') FROM fs;
-- error: fda_train: unknown option "states" (expected joints, normalize, scale, up, velocity, frame, root, progress, method, basis, order, lambda, dims, kernel, sigma, ffda_reg, isomap_k, proto_dims, alignment)
SELECT fda_train(m, 'sad') FROM fs;
-- error: fda_train: need motions of at least 2 labels, got 1 ("sad")
SELECT fda_train(m, x'00') FROM fs;
-- error: fda_train: row 1: label must be text or a number, got a BLOB
SELECT 'F-Isomap joins a 1-NN graph in pieces by the shortest distances between them: every motion embeds, 1-NN right on its training waves',
       sum(fda_classify(model, m, 1) = emotion) = 24
  FROM (SELECT fda_train(m, emotion, '{"basis":20,"method":"fisomap","isomap_k":1}') AS model FROM fs), fs;
-- oom: skip
SELECT fda_prototype(model, 'joy') FROM fm WHERE method = 'small';
-- error: fda_prototype: no class "joy" in the model (angry, happy, neutral, sad)
SELECT fda_plot(model, '{"y":5}') FROM fm WHERE method = 'small';
-- error: fda_plot: option "y" must be from 1 to 2 (the model's dimensions), got 5
SELECT fda_classify(model, m, 0) FROM fm, fs WHERE method = 'small' LIMIT 1;
-- error: fda_classify: k must be from 1 to 100000, got 0
SELECT fda_plot(model, '{"axis":3,"coordinate":1}') FROM fm WHERE method = 'small';
-- error: fda_plot: axis 3 is out of range (2 dimensions)
SELECT fda_plot(model, '{"coordinate":4}') FROM fm WHERE method = 'small';
-- error: fda_plot: coordinate 4 is out of range (3 coordinates)
SELECT fda_plot(model, '{"coordinate":1}') FROM fm WHERE method = 'fisomap';
-- error: fda_plot: perturbation plots need a linear method (fpca, ffda, fspca), not fisomap
