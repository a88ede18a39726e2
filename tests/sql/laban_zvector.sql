-- laban_zvector.sql — SQL-level specification of laban_zvector (ext/fn_laban.c; core:
-- affect_laban_l2_vector in core/laban/laban_std.c): a motion's Laban vector standardized with a
-- laban index's statistics, as float32, so that plain L2 distances between such vectors are the
-- index's distances (sqlite-vec's vec0 then finds the index's neighbours: tests/client/
-- sqlite_vec_test.sh checks that with the real vec0). Here the float32 BLOBs are decoded in SQL
-- and checked against laban_vector, the index's _info statistics and the index's own distances.
-- Run by tests/sql/test_sql.c; see its header for the annotations.

CREATE TABLE motions(id INTEGER PRIMARY KEY, content TEXT, emotion TEXT, motion BLOB);
INSERT INTO motions(content, emotion, motion)
SELECT a.value, e.value, motion_synth(a.value, e.value, k.value)
  FROM json_each('["knock","wave","walk","bow"]') AS a,
       json_each('["neutral","happy","sad","angry"]') AS e,
       json_each('[1,2]') AS k;

CREATE VIRTUAL TABLE motion_laban USING laban(content=motions, motion=motion, label=emotion);

-- ---- registration: it reads the index, so direct-only and not deterministic ----
SELECT group_concat(name || '/' || narg, ' ') FROM (
  SELECT DISTINCT name, narg FROM pragma_function_list WHERE name = 'laban_zvector'
   ORDER BY name, narg);
-- expect: laban_zvector/2 laban_zvector/3

SELECT 'not deterministic, direct-only', count(*) = 2 FROM pragma_function_list
 WHERE name = 'laban_zvector' AND (flags & 0x000000800) = 0 AND (flags & 0x000080000) <> 0;

-- ---- float32 decoded in SQL: f32(i, x) of every component of a BLOB ----
-- bits = little-endian bytes; sign, exponent, mantissa (normal and subnormal numbers; NaN and
-- inf, exponent 255, come out as NULL)
CREATE TEMP TABLE vecs(id INTEGER, kind TEXT, blob BLOB);
CREATE TEMP TABLE idx27(i INTEGER PRIMARY KEY);
WITH RECURSIVE n(i) AS (SELECT 0 UNION ALL SELECT i + 1 FROM n WHERE i < 26)
INSERT INTO idx27 SELECT i FROM n;

CREATE TEMP VIEW bits AS
SELECT id, kind, i, b0 + 256 * b1 + 65536 * b2 + 16777216 * b3 AS u FROM (
  SELECT id, kind, i,
         (instr('0123456789ABCDEF', substr(h, 1, 1)) - 1) * 16 +
          instr('0123456789ABCDEF', substr(h, 2, 1)) - 1 AS b0,
         (instr('0123456789ABCDEF', substr(h, 3, 1)) - 1) * 16 +
          instr('0123456789ABCDEF', substr(h, 4, 1)) - 1 AS b1,
         (instr('0123456789ABCDEF', substr(h, 5, 1)) - 1) * 16 +
          instr('0123456789ABCDEF', substr(h, 6, 1)) - 1 AS b2,
         (instr('0123456789ABCDEF', substr(h, 7, 1)) - 1) * 16 +
          instr('0123456789ABCDEF', substr(h, 8, 1)) - 1 AS b3
    FROM (SELECT v.id, v.kind, idx27.i, hex(substr(v.blob, 4 * idx27.i + 1, 4)) AS h
            FROM vecs AS v JOIN idx27 ON 4 * idx27.i < length(v.blob)));

CREATE TEMP VIEW f32 AS
SELECT id, kind, i,
       CASE WHEN (u >> 23) & 255 = 255 THEN NULL
            WHEN (u >> 23) & 255 = 0 THEN (1 - 2 * (u >> 31)) * (u & 8388607) * power(2, -149)
            ELSE (1 - 2 * (u >> 31)) * (1 + (u & 8388607) / 8388608.0)
                 * power(2, ((u >> 23) & 255) - 127) END AS x
  FROM bits;

-- the raw vectors, the standardized ones (all 27 and TimeAll + FlowAll) and their statistics
INSERT INTO vecs SELECT id, 'raw', laban_vector(motion) FROM motions;
INSERT INTO vecs SELECT id, 'z', laban_zvector(motion, 'motion_laban') FROM motions;
INSERT INTO vecs SELECT id, 'tf', laban_zvector(motion, 'motion_laban',
                                                '{"components":["FlowAll","TimeAll"]}')
  FROM motions;
CREATE TEMP TABLE dec AS SELECT * FROM f32;
CREATE TEMP TABLE stats AS
SELECT idx27.i, json_extract(m.value, '$[' || idx27.i || ']') AS mean,
       json_extract(s.value, '$[' || idx27.i || ']') AS sd
  FROM idx27, motion_laban_info AS m, motion_laban_info AS s
 WHERE m.key = 'mean' AND s.key = 'sd';

SELECT 'the decoder reads laban_vector as the index''s columns give it', count(*) = 32
  FROM motion_laban AS l JOIN dec AS d ON d.id = l.rowid AND d.kind = 'raw' AND d.i = 0
  JOIN dec AS t ON t.id = l.rowid AND t.kind = 'raw' AND t.i = 7
 WHERE d.x = l.WeightAll AND t.x = l.TimeAll;

SELECT 'a float32 BLOB of 27 values (108 bytes), of 2 with two components', count(*) = 64
  FROM vecs WHERE (kind = 'z' AND length(blob) = 108) OR (kind = 'tf' AND length(blob) = 8);

SELECT 'z = (raw - mean) / sd with the index''s mean and sd, rounded to float32',
       count(*) = 32 * 27
  FROM dec AS r JOIN dec AS z ON z.id = r.id AND z.i = r.i AND z.kind = 'z'
  JOIN stats USING (i)
 WHERE r.kind = 'raw'
   AND abs(z.x - (r.x - stats.mean) / stats.sd) <= 6e-8 * abs((r.x - stats.mean) / stats.sd);

SELECT 'components: the chosen ones, in laban_names() order', count(*) = 32
  FROM dec AS a JOIN dec AS b ON b.id = a.id AND b.kind = 'tf'
  JOIN dec AS t ON t.id = a.id AND t.kind = 'z' AND t.i = 7
  JOIN dec AS f ON f.id = a.id AND f.kind = 'z' AND f.i = 14
 WHERE a.kind = 'tf' AND a.i = 0 AND b.i = 1 AND a.x = t.x AND b.x = f.x;

SELECT 'the z-scores of the indexed rows have mean 0 and sd 1', count(*) = 27
  FROM (SELECT i, avg(x) AS m, sqrt(sum(x * x) / (count(*) - 1) - avg(x) * avg(x) * count(*)
                                    / (count(*) - 1)) AS s
          FROM dec WHERE kind = 'z' GROUP BY i)
 WHERE abs(m) < 1e-6 AND abs(s - 1) < 1e-5;

-- ---- the L2 distances of the vectors are the index's distances ----
CREATE TEMP TABLE l2 AS
SELECT a.id AS q, b.id AS id, a.kind AS kind, sqrt(sum((a.x - b.x) * (a.x - b.x))) AS d
  FROM dec AS a JOIN dec AS b ON b.i = a.i AND b.kind = a.kind AND b.id <> a.id
 WHERE a.kind IN ('z', 'tf')
 GROUP BY a.id, b.id, a.kind;

CREATE TEMP TABLE ix AS
SELECT q.id AS q, l.rowid AS id, 'z' AS kind, l.distance AS d
  FROM motions AS q, motion_laban AS l WHERE l.query = q.id AND l.k = 100
UNION ALL
SELECT q.id, l.rowid, 'tf', l.distance
  FROM motions AS q, motion_laban AS l
 WHERE l.query = q.id AND l.k = 100 AND l.components = '["TimeAll","FlowAll"]';
-- oom: skip

SELECT 'every pair: L2 of the vectors = the index''s distance (float32 rounding)',
       count(*) = 2 * 32 * 31
  FROM l2 JOIN ix USING (q, id, kind) WHERE abs(l2.d - ix.d) <= 1e-6 * (1 + ix.d);
-- oom: skip

SELECT 'every query: the 5 nearest by L2 are the index''s 5 nearest', count(*) = 2 * 32
  FROM (SELECT q, kind, group_concat(id) AS ids FROM
          (SELECT q, kind, id, row_number() OVER (PARTITION BY q, kind ORDER BY d, id) AS r
             FROM l2) WHERE r <= 5 GROUP BY q, kind) AS a
  JOIN (SELECT q, kind, group_concat(id) AS ids FROM
          (SELECT q, kind, id, row_number() OVER (PARTITION BY q, kind ORDER BY d, id) AS r
             FROM ix) WHERE r <= 5 GROUP BY q, kind) AS b USING (q, kind)
 WHERE a.ids = b.ids;
-- oom: skip

-- ---- NULL in, NULL out ----
SELECT laban_zvector(NULL, 'motion_laban') IS NULL,
       laban_zvector(motion, NULL) IS NULL,
       length(laban_zvector(motion, 'motion_laban', NULL))
  FROM motions WHERE id = 1;
-- expect: 1

SELECT length(laban_zvector(motion, 'motion_laban', NULL)) FROM motions WHERE id = 1;
-- expect: 108

-- ---- arguments and options ----
SELECT laban_zvector(x'00', 'motion_laban');
-- error: laban_zvector: argument 1 is not a valid motion: truncated: 1 bytes is shorter than the 32-byte header

SELECT laban_zvector(motion, 'nope') FROM motions WHERE id = 1;
-- error: laban_zvector: "nope" is not a laban table (CREATE VIRTUAL TABLE nope USING laban(…))

SELECT laban_zvector(motion, 'motions') FROM motions WHERE id = 1;
-- error: laban_zvector: "motions" is not a laban table (CREATE VIRTUAL TABLE motions USING laban(…))

-- an index is known by its module (the statement read token by token), however the statement
-- is written: a quoted name, a comment, the module's name in capitals, a blank before "("
CREATE VIRTUAL TABLE "odd ""name""" /* a comment */ USING LABAN (content=motions, motion=motion, label=emotion);
SELECT 'quoted name, comment, module in capitals',
       laban_zvector(m, 'odd "name"') = laban_zvector(m, 'motion_laban')
  FROM (SELECT motion AS m FROM motions WHERE id = 1);
DROP TABLE "odd ""name""";

-- and not by its name: this plain table's name holds "USING laban(", and a table beside it
-- looks like its _info
CREATE TABLE "fake USING laban(" (x);
CREATE TABLE "fake USING laban(_info"(key TEXT PRIMARY KEY, value);
INSERT INTO "fake USING laban(_info"
VALUES ('format', '1'), ('content', 'motions'), ('motion', 'motion');
SELECT laban_zvector(motion, 'fake USING laban(') FROM motions WHERE id = 1;
-- error: laban_zvector: "fake USING laban(" is not a laban table (CREATE VIRTUAL TABLE fake USING laban( USING laban(…))

DROP TABLE "fake USING laban(";
DROP TABLE "fake USING laban(_info";

SELECT laban_zvector(motion, 7) FROM motions WHERE id = 1;
-- error: laban_zvector: "7" is not a laban table (CREATE VIRTUAL TABLE 7 USING laban(…))

SELECT laban_zvector(motion, x'6d6f74696f6e5f6c6162616e') FROM motions WHERE id = 1;
-- error: laban_zvector: argument 2 must be text, got blob

SELECT laban_zvector(motion, 'motion_laban', '{"components":"TimeAll"}') FROM motions WHERE id = 1;
-- error: laban_zvector: option "components" must be a non-empty array of component names (see laban_names()), got string

SELECT laban_zvector(motion, 'motion_laban', '{"components":[]}') FROM motions WHERE id = 1;
-- error: laban_zvector: option "components" must be a non-empty array of component names (see laban_names()), got an empty array

SELECT laban_zvector(motion, 'motion_laban', '{"components":["TimeAll",3]}') FROM motions WHERE id = 1;
-- error: laban_zvector: option "components" must be an array of component names, got number in it

SELECT laban_zvector(motion, 'motion_laban', '{"components":["Time"]}') FROM motions WHERE id = 1;
-- error: laban_zvector: option "components": unknown component "Time" (see laban_names())

SELECT laban_zvector(motion, 'motion_laban', '{"components":["TimeAll","TimeAll"]}') FROM motions WHERE id = 1;
-- error: laban_zvector: option "components": component "TimeAll" is listed twice

SELECT laban_zvector(motion, 'motion_laban', '{"cutoff_hz":3}') FROM motions WHERE id = 1;
-- error: laban_zvector: unknown option "cutoff_hz" (expected components)

SELECT laban_zvector(motion, 'motion_laban', '[1]') FROM motions WHERE id = 1;
-- error: laban_zvector: options (argument 3) must be a JSON object, got array

SELECT laban_vector(motion, '{"standardize":"motion_laban"}') FROM motions WHERE id = 1;
-- error: laban_vector: option "standardize" is laban_zvector's: laban_zvector(motion, 'index_name') gives the vector standardized with that laban index's statistics (laban_vector is pure and reads no table)

-- ---- the index's options: a motion's vector is computed as the index computes it ----
CREATE VIRTUAL TABLE boxed USING laban(content=motions, motion=motion, label=emotion,
                                       options='{"hull":"box","cutoff_hz":4}');

SELECT 'with the index''s options (the boxed index differs from the plain one)',
       laban_zvector(motion, 'boxed') <> laban_zvector(motion, 'motion_laban')
   AND (SELECT group_concat(rowid) FROM boxed WHERE query = 1 AND k = 3) IS NOT NULL
  FROM motions WHERE id = 1;

-- the f32 view reads vecs: refill it with the boxed vectors
CREATE TEMP TABLE boxed_l2(id INTEGER, d2 REAL);
DELETE FROM vecs;
INSERT INTO vecs SELECT id, 'boxed', laban_zvector(motion, 'boxed') FROM motions;
INSERT INTO boxed_l2
SELECT a.id, sum((a.x - q.x) * (a.x - q.x)) FROM f32 AS a JOIN f32 AS q ON q.i = a.i AND q.id = 1
 WHERE a.id <> 1 GROUP BY a.id;
-- oom: skip

SELECT 'L2 of the boxed vectors = the boxed index''s distances', count(*) = 31
  FROM boxed_l2 JOIN boxed AS b ON b.rowid = boxed_l2.id
 WHERE b.query = 1 AND b.k = 100 AND abs(sqrt(boxed_l2.d2) - b.distance) <= 1e-6 * (1 + b.distance);

-- ---- missing components ----
CREATE TABLE small(id INTEGER PRIMARY KEY, tag TEXT, m BLOB);
INSERT INTO small VALUES
    (1, 'sad', motion_synth('walk', 'sad', 1)),
    (2, 'happy', motion_synth('walk', 'happy', 1)),
    (3, 'angry', motion_synth('walk', 'angry', 1));
CREATE TEMP TABLE legs AS SELECT motion_select(motion_synth('walk', 'angry', 2),
        '["Hips","Spine","Chest","Neck","Head","UpperLeg_L","LowerLeg_L","Foot_L",' ||
        '"UpperLeg_R","LowerLeg_R","Foot_R"]') AS m;
CREATE VIRTUAL TABLE small_laban USING laban(content=small, motion=m, label=tag);

SELECT laban_zvector(m, 'small_laban') FROM legs;
-- error: laban_zvector: component WeightAll is missing in this motion but present in the index, so no L2 vector gives the index's distances (index "small_laban"; leave it out with {"components": […]})

SELECT 'without the missing components it works',
       length(laban_zvector(m, 'small_laban', '{"components":["WeightTorso","TimeHead"]}')) = 8
  FROM legs;

-- a component missing in every indexed row has a null mean: it is 0 in every vector (the index
-- skips it for every pair)
CREATE TABLE handless(id INTEGER PRIMARY KEY, label TEXT, m BLOB);
INSERT INTO handless SELECT 1, 'angry', m FROM legs;
INSERT INTO handless SELECT 2, 'sad', motion_select(motion_synth('walk', 'sad', 2),
        '["Hips","Spine","Chest","Neck","Head","UpperLeg_L","LowerLeg_L","Foot_L",' ||
        '"UpperLeg_R","LowerLeg_R","Foot_R"]');
CREATE VIRTUAL TABLE handless_laban USING laban(content=handless, motion=m);

SELECT 'a component missing everywhere is 0 (WeightAll, WeightLHand: bytes 0-3, 12-15)',
       hex(substr(v, 1, 4)) = '00000000' AND hex(substr(v, 13, 4)) = '00000000'
   AND hex(substr(v, 5, 4)) <> '00000000'
  FROM (SELECT laban_zvector(m, 'handless_laban') AS v FROM handless WHERE id = 1);

SELECT 'and is 0 for a motion that has it', hex(substr(v, 1, 4)) = '00000000'
  FROM (SELECT laban_zvector(m, 'handless_laban') AS v FROM small WHERE id = 1);

-- ---- statistics read back as untrusted input ----
-- Each damage is written straight into _info, as a damaged file or a stray UPDATE would leave
-- it, and undone afterwards; 'rebuild' would rewrite the statistics at commit.
CREATE TEMP TABLE saved AS SELECT key, value FROM small_laban_info;

UPDATE small_laban_info SET value = json_replace(value, '$[3]', -1) WHERE key = 'sd';
SELECT laban_zvector(m, 'small_laban') FROM small WHERE id = 1;
-- error: laban_zvector: corrupt statistics: sd[3] (WeightLHand) is -1, expected a finite number > 0 (index "small_laban", small_laban_info row 'sd'); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_info SET value = json_replace(value, '$[3]', 0) WHERE key = 'sd';
SELECT laban_zvector(m, 'small_laban') FROM small WHERE id = 1;
-- error: laban_zvector: corrupt statistics: sd[3] (WeightLHand) is 0, expected a finite number > 0 (index "small_laban", small_laban_info row 'sd'); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_info SET value = replace(json_remove(value, '$[3]'), '[', '[1e999,') WHERE key = 'sd';
SELECT laban_zvector(m, 'small_laban') FROM small WHERE id = 1;
-- error: laban_zvector: corrupt statistics: sd is not valid JSON (at byte 1: number out of range) (index "small_laban", small_laban_info row 'sd'); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_info SET value = json_remove((SELECT value FROM saved WHERE key = 'sd'), '$[3]')
 WHERE key = 'sd';
SELECT laban_zvector(m, 'small_laban') FROM small WHERE id = 1;
-- error: laban_zvector: corrupt statistics: sd is a JSON array of 26 values, expected 27 (index "small_laban", small_laban_info row 'sd'); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_info SET value = '{"sd":1}' WHERE key = 'sd';
SELECT laban_zvector(m, 'small_laban') FROM small WHERE id = 1;
-- error: laban_zvector: corrupt statistics: sd is a JSON object, expected an array of 27 numbers (index "small_laban", small_laban_info row 'sd'); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_info SET value = x'5b315d' WHERE key = 'sd';
SELECT laban_zvector(m, 'small_laban') FROM small WHERE id = 1;
-- error: laban_zvector: corrupt statistics: sd is not text, expected a JSON array of 27 numbers (index "small_laban", small_laban_info row 'sd'); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

DELETE FROM small_laban_info WHERE key = 'sd';
SELECT laban_zvector(m, 'small_laban') FROM small WHERE id = 1;
-- error: laban_zvector: corrupt statistics: sd is missing or NULL, expected a JSON array of 27 numbers (index "small_laban", small_laban_info row 'sd'); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

INSERT INTO small_laban_info SELECT key, value FROM saved WHERE key = 'sd';
UPDATE small_laban_info SET value = json_replace(value, '$[5]', 'x') WHERE key = 'mean';
SELECT laban_zvector(m, 'small_laban') FROM small WHERE id = 1;
-- error: laban_zvector: corrupt statistics: mean[5] (WeightLFoot) is string, expected a number or null (index "small_laban", small_laban_info row 'mean'); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_info SET value = '[1,2' WHERE key = 'mean';
SELECT laban_zvector(m, 'small_laban') FROM small WHERE id = 1;
-- error: laban_zvector: corrupt statistics: mean is not valid JSON (at byte 4: unexpected end of text) (index "small_laban", small_laban_info row 'mean'); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_info SET value = (SELECT value FROM saved WHERE key = 'mean') WHERE key = 'mean';
UPDATE small_laban_info SET value = '{"hull":"sphere"}' WHERE key = 'options';
SELECT laban_zvector(m, 'small_laban') FROM small WHERE id = 1;
-- error: laban_zvector: corrupt statistics: options: option "hull" must be "convex" or "box", got "sphere" (index "small_laban", small_laban_info row 'options'); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_info SET value = (SELECT value FROM saved WHERE key = 'options') WHERE key = 'options';
UPDATE small_laban_info SET value = 'many' WHERE key = 'rows';
SELECT laban_zvector(m, 'small_laban') FROM small WHERE id = 1;
-- error: laban_zvector: corrupt statistics: rows is text, expected an integer >= 0 (index "small_laban", small_laban_info row 'rows'); run INSERT INTO small_laban(small_laban) VALUES('rebuild')

UPDATE small_laban_info SET value = (SELECT value FROM saved WHERE key = 'rows') WHERE key = 'rows';
UPDATE small_laban_info SET value = '2' WHERE key = 'format';
SELECT laban_zvector(m, 'small_laban') FROM small WHERE id = 1;
-- error: laban_zvector: small_laban_info has format "2"; this version reads format 1 (index "small_laban")

UPDATE small_laban_info SET value = '1' WHERE key = 'format';
-- the generation moves on without the statistics (what a transaction that changed the index
-- shows until it commits)
UPDATE small_laban_info SET value = value + 1 WHERE key = 'generation';
SELECT laban_zvector(m, 'small_laban') FROM small WHERE id = 1;
-- error: laban_zvector: the statistics of index "small_laban" are out of date until the transaction that changed it commits (generation 2, statistics of generation 1)

UPDATE small_laban_info SET value = value - 1 WHERE key = 'generation';
SELECT 'the damage undone, it works again', count(*) = 0,
       length(laban_zvector((SELECT m FROM small WHERE id = 1), 'small_laban')) = 108
  FROM (SELECT key, value FROM small_laban_info EXCEPT SELECT key, value FROM saved);

-- an index written before stats_generation existed is taken as current
DELETE FROM small_laban_info WHERE key = 'stats_generation';
SELECT 'without stats_generation', length(laban_zvector(m, 'small_laban')) = 108
  FROM small WHERE id = 1;

-- its statistics are rewritten by a rebuild (at commit), stats_generation with them
INSERT INTO small_laban(small_laban) VALUES('rebuild');
SELECT 'a rebuild writes stats_generation = generation', a.value = b.value
  FROM small_laban_info AS a, small_laban_info AS b
 WHERE a.key = 'stats_generation' AND b.key = 'generation';
