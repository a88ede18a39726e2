-- laban_series.sql — SQL-level specification of laban_series, the table-valued function of
-- Weight, Time, Space and Flow over a sliding window (issue 17 item 4). Run by
-- tests/sql/test_sql.c; see its header for the annotations.

CREATE TABLE ls(action TEXT, emotion TEXT, m BLOB);
INSERT INTO ls
SELECT a.value, e.value, motion_synth(a.value, e.value, 1)
  FROM json_each('["knock","walk"]') AS a, json_each('["sad","angry"]') AS e;

SELECT 'the module is registered', count(*) = 1 FROM pragma_module_list
 WHERE name = 'laban_series';

SELECT group_concat(name, ' ') FROM pragma_table_xinfo('laban_series');
-- expect: frame seconds first_frame last_frame part weight time space flow motion options

-- ---- the default layout: one-second windows, a one-frame hop, seven rows per window ----
SELECT 'default: windows of fps frames, hop 1, the seven parts in order',
       (SELECT count(*) FROM laban_series(m)) =
           7 * (motion_frames(m) - CAST(json_extract(motion_info(m), '$.fps') AS INTEGER) + 1)
   AND (SELECT group_concat(part, ' ') FROM laban_series(m) WHERE first_frame = 0) =
           'all torso head left_hand right_hand left_foot right_foot'
   AND (SELECT max(last_frame - first_frame + 1) = min(last_frame - first_frame + 1)
               AND min(last_frame - first_frame + 1) =
                   CAST(json_extract(motion_info(m), '$.fps') AS INTEGER)
          FROM laban_series(m))
  FROM ls;
-- oom: skip

SELECT 'frame is the centre frame (rounded down), seconds the centre time',
       (SELECT count(*) FROM laban_series(m, '{"window_frames":10,"hop_frames":7}')
         WHERE frame <> first_frame + (last_frame - first_frame) / 2
            OR abs(seconds - (first_frame + last_frame) / 2.0
                   / json_extract(motion_info(m), '$.fps')) > 1e-12
            OR first_frame % 7 <> 0) = 0
  FROM ls;
-- oom: skip

-- ---- a window covering the whole take is the per-clip value ----
SELECT 'whole window: ' || s.part || ' of ' || action || ' ' || emotion,
       s.weight = laban_weight(m, s.part) AND s.time = laban_time(m, s.part)
   AND abs(s.space - laban_space(m, s.part)) <= 1e-12 * laban_space(m, s.part)
   AND abs(s.flow - laban_flow(m, s.part)) <= 1e-12 * laban_flow(m, s.part)
   AND s.first_frame = 0 AND s.last_frame = motion_frames(m) - 1
  FROM ls, laban_series(ls.m, '{"window":1000}') AS s;
-- oom: skip

SELECT 'whole window, the other methods: ' || s.part || ' of ' || action || ' ' || emotion,
       s.weight = laban_weight(m, s.part, '{"method":"deceleration"}')
   AND abs(s.time - laban_time(m, s.part, '{"method":"accumulated","per_second":true}'))
       <= 1e-12 * s.time
  FROM ls, laban_series(ls.m, '{"window_frames":100000,"weight_method":"deceleration",' ||
                              '"time_method":"accumulated","per_second":true}') AS s;
-- oom: skip

-- the peaks of the windows of a one-frame hop cover every frame: their maximum is the clip's
SELECT 'max over windows = the per-clip peak: ' || action || ' ' || emotion,
       (SELECT max(weight) FROM laban_series(m, '{"window":0.5,"parts":"all"}')) =
           laban_weight(m)
   AND (SELECT max(time) FROM laban_series(m, '{"window":0.5,"parts":"all"}')) = laban_time(m)
  FROM ls;
-- oom: skip

SELECT 'angry is Strong and Sudden over most of the take, sad Light and Sustained',
       (SELECT avg(weight) FROM laban_series(a.m) WHERE part = 'all') >
           2 * (SELECT avg(weight) FROM laban_series(s.m) WHERE part = 'all')
   AND (SELECT avg(time) FROM laban_series(a.m) WHERE part = 'all') >
           (SELECT avg(time) FROM laban_series(s.m) WHERE part = 'all')
  FROM ls AS a JOIN ls AS s USING (action) WHERE a.emotion = 'angry' AND s.emotion = 'sad';
-- oom: skip

-- ---- options ----
SELECT 'parts: a name, an array in its order, a joint',
       (SELECT group_concat(DISTINCT part) FROM laban_series(m, '{"parts":"head"}')) = 'head'
   AND (SELECT group_concat(part, ' ') FROM laban_series(m, '{"parts":["right_hand","all"]}')
         WHERE first_frame = 0) = 'right_hand all'
   AND (SELECT weight FROM laban_series(m, '{"parts":"Head","window":100}')) =
       (SELECT weight FROM laban_series(m, '{"parts":"head","window":100}'))
  FROM ls WHERE action = 'knock' AND emotion = 'sad';

SELECT 'window longer than the take: one window; hop longer than the window',
       (SELECT count(*) FROM laban_series(m, '{"window":1e9,"parts":"all"}')) = 1
   AND (SELECT count(*) FROM laban_series(m, '{"window_frames":5,"hop":2,"parts":"all"}')) =
       (motion_frames(m) - 5) / 60 + 1
  FROM ls WHERE action = 'knock' AND emotion = 'sad';

SELECT 'missing null: rows of NULL for a part without its role, and for all',
       (SELECT count(*) FROM laban_series(m, '{"roles":{"head":null},"missing":"null"}')
         WHERE part IN ('head', 'all') AND weight IS NULL AND time IS NULL AND space IS NULL
           AND flow IS NULL) =
       (SELECT count(*) FROM laban_series(m, '{"parts":["head","all"]}'))
   AND (SELECT count(*) FROM laban_series(m, '{"roles":{"head":null},"missing":"null"}')
         WHERE part NOT IN ('head', 'all') AND weight IS NULL) = 0
  FROM ls WHERE action = 'knock' AND emotion = 'sad';

SELECT 'a NULL motion gives no rows; NULL options are the defaults',
       (SELECT count(*) FROM laban_series(NULL)) = 0
   AND (SELECT count(*) FROM laban_series(m, NULL)) = (SELECT count(*) FROM laban_series(m))
  FROM ls WHERE action = 'knock' AND emotion = 'sad';

SELECT 'a motion of three frames: an error, or no rows with missing null',
       (SELECT count(*) FROM laban_series(motion_slice(m, 0, 2), '{"missing":"null"}')) = 0
  FROM ls WHERE action = 'knock' AND emotion = 'sad';

-- ---- laban_plot's time-series mode over the series ----
SELECT 'laban_plot mode series: one line per part, in x order',
       svg LIKE '<svg xmlns=%</svg>' || char(10)
   AND instr(svg, '<g class="lines"') > 0 AND instr(svg, 'class="points"') = 0
   AND (length(svg) - length(replace(svg, '<path d="M', ''))) / length('<path d="M') = 7
   AND instr(svg, 'data-label="left_hand" data-count="70"') > 0
  FROM (SELECT laban_plot(seconds, weight, part, '{"mode":"series","y_label":"Weight"}') AS svg
          FROM laban_series((SELECT m FROM ls WHERE action = 'knock' AND emotion = 'angry')));
-- oom: skip

SELECT laban_plot(1, 2, 'a', '{"mode":"lines"}');
-- error: laban_plot: option "mode" must be one of "scatter", "series", got "lines"

-- ---- errors ----
SELECT * FROM laban_series(motion_slice((SELECT m FROM ls LIMIT 1), 0, 2));
-- error: laban_series: the motion has 3 frames; the Laban series needs at least 4
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{"window":0.01}');
-- error: laban_series: option "window" must be at least 2 frames (0.05 s at 30 fps), got 0.01 s
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{"window":1,"window_frames":30}');
-- error: laban_series: give "window" or "window_frames", not both
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{"hop_frames":0}');
-- error: laban_series: option "hop_frames" must be an integer of at least 1, got 0
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{"window_frames":2.5}');
-- error: laban_series: option "window_frames" must be an integer of at least 2, got 2.5
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{"hop":"1"}');
-- error: laban_series: option "hop" must be a number, got string
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{"wndow":1}');
-- error: laban_series: unknown option "wndow" (expected window, window_frames, hop, hop_frames, parts, weight_method, time_method, per_second, max_ratio, cutoff_hz, up, roles, missing)
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{"weight_method":"max"}');
-- error: laban_series: option "weight_method" must be one of "peak", "deceleration", got "max"
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{"parts":["head","head"]}');
-- error: laban_series: option "parts" names "head" twice
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{"parts":[]}');
-- error: laban_series: option "parts" must name 1 to 16 parts, got 0
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{"parts":[1]}');
-- error: laban_series: option "parts": every element must be a part name, got number
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{"parts":["all","Hips"]}');
-- error: laban_series: option "parts": at most 6 distinct parts ("all" counts as its six), and "Hips" is a seventh
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{"parts":"nose"}');
-- error: laban_series: "nose" is neither a part (all, torso, head, left_hand, right_hand, left_foot, right_foot) nor a joint of the motion
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{"roles":{"head":null}}');
-- error: laban_series: no joint has the head role (assign it with {"roles": {…}}, or use {"missing": "null"})
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{"cutoff_hz":0}');
-- error: laban_series: cutoff_hz must be a positive number, got 0
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '[1]');
-- error: laban_series: options must be a JSON object, got array
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), '{');
-- error: laban_series: options are not valid JSON: at byte 1: unexpected end of text
SELECT * FROM laban_series((SELECT m FROM ls LIMIT 1), 7);
-- error: laban_series: options must be a JSON object as text, got integer
SELECT * FROM laban_series('walk');
-- error: laban_series: the argument must be a motion BLOB, got text
SELECT * FROM laban_series(x'00010203');
-- error: laban_series: the argument is not a valid motion: truncated: 4 bytes is shorter than the 32-byte header
SELECT * FROM laban_series;
-- error: laban_series: a motion argument is required, as in SELECT * FROM laban_series(:motion)
