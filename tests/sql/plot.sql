-- plot.sql — SQL-level specification of the laban_plot aggregate (an SVG scatter plot).
-- Run by tests/sql/test_sql.c (see its header for the annotation format); each SELECT without
-- an annotation must give 1 in its second column.

CREATE TABLE pts(x, y, label);
INSERT INTO pts VALUES (1, 2, 'sad'), (2, 3, 'angry'), (3, 1, 'sad'), (4, 5, NULL),
                       (NULL, 1, 'sad'), (5, NULL, 'happy'), (6, 6, 42), (7.5, 0.25, 'angry');

-- ---- registration ----
SELECT group_concat(name || '/' || narg || '/' || type, ' ') FROM (
  SELECT DISTINCT name, narg, type FROM pragma_function_list WHERE name = 'laban_plot'
   ORDER BY narg);
-- expect: laban_plot/3/a laban_plot/4/a

SELECT 'laban_plot is deterministic and innocuous', count(*) = 2 FROM pragma_function_list
 WHERE name = 'laban_plot' AND (flags & 0x000000800) <> 0 AND (flags & 0x000200000) <> 0;

-- ---- points, legend counts, skipped rows ----
SELECT substr(laban_plot(x, y, label), 1, 112) FROM pts;
-- expect: <svg xmlns="http://www.w3.org/2000/svg" width="560" height="420" viewBox="0 0 560 420" font-family="sans-serif">

-- NULL x or y: the row is skipped (no point, no legend row, no note); a number label is text;
-- a NULL label is "(none)"
WITH p(svg) AS (SELECT laban_plot(x, y, label) FROM pts)
SELECT 'legend rows with counts',
       instr(svg, '>(none) <tspan fill="#777">(1)</tspan>') > 0
   AND instr(svg, '>42 <tspan fill="#777">(1)</tspan>') > 0
   AND instr(svg, '>angry <tspan fill="#777">(2)</tspan>') > 0
   AND instr(svg, '>sad <tspan fill="#777">(2)</tspan>') > 0
   AND instr(svg, 'happy') = 0
   AND instr(svg, 'class="note"') = 0
   AND instr(svg, 'no data') = 0 FROM p;

WITH p(svg) AS (SELECT laban_plot(x, y, label) FROM pts)
SELECT 'one circle per point and per legend row',
       (length(svg) - length(replace(svg, '<circle', ''))) / 7 = 6 + 4 FROM p;

WITH p(svg) AS (SELECT laban_plot(x, y, label) FROM pts)
SELECT 'series in label order, Okabe-Ito colours',
       instr(svg, 'data-label="(none)" data-count="1" fill="#0072B2"') > 0
   AND instr(svg, 'data-label="42" data-count="1" fill="#E69F00"') > 0
   AND instr(svg, 'data-label="angry" data-count="2" fill="#009E73"') > 0
   AND instr(svg, 'data-label="sad" data-count="2" fill="#D55E00"') > 0 FROM p;

SELECT 'the order of rows does not matter',
       (SELECT laban_plot(x, y, label) FROM (SELECT * FROM pts ORDER BY x)) =
       (SELECT laban_plot(x, y, label) FROM (SELECT * FROM pts ORDER BY x DESC));

-- non-finite values are drawn as skipped, in the note
SELECT 'an infinite value is a skipped point',
       instr(laban_plot(x, y, 'a'), '>skipped 1 of 3 points: 1 not finite</text>') > 0
  FROM (SELECT 1e999 AS x, 1 AS y UNION ALL SELECT 1, 2 UNION ALL SELECT 2, 1);

SELECT 'no rows: the empty plot', instr(laban_plot(x, y, label), '>no data</text>') > 0
  FROM pts WHERE 0;

SELECT 'only NULL rows: the empty plot with the options',
       instr(laban_plot(x, y, label, '{"title":"empty"}'), '>empty</text>') > 0
   AND instr(laban_plot(x, y, label, '{"title":"empty"}'), '>no data</text>') > 0
  FROM pts WHERE x IS NULL OR y IS NULL;

SELECT 'one plot per group', count(*) = 3, sum(svg LIKE '<svg %</svg>' || char(10)) = 3,
       sum(instr(svg, 'data-count="2"') > 0) = 2
  FROM (SELECT label, laban_plot(x, y, label) AS svg FROM pts
         WHERE label IS NOT NULL AND x IS NOT NULL AND y IS NOT NULL GROUP BY label);

SELECT 'a GROUP BY cut short by LIMIT', count(*) = 1
  FROM (SELECT label, laban_plot(x, y, label) FROM pts GROUP BY label LIMIT 1);

-- ---- options ----
WITH p(svg) AS (
  SELECT laban_plot(x, y, label, '{"width":800,"height":300,"title":"Weight vs Time",
                                   "x_label":"WeightAll","y_label":"TimeAll","log_x":true,
                                   "log_y":true,"radius":4,"means":true}')
    FROM pts)
SELECT 'every option', instr(svg, 'width="800" height="300" viewBox="0 0 800 300"') > 0
   AND instr(svg, '>Weight vs Time</text>') > 0
   AND instr(svg, '>WeightAll</text>') > 0
   AND instr(svg, '>TimeAll</text>') > 0
   AND instr(svg, ' r="4"') > 0
   AND instr(svg, 'class="grid-minor"') > 0
   AND instr(svg, 'data-label="sad" data-n="2"') > 0
   AND instr(svg, 'mean ± 1 sd') > 0 FROM p;

SELECT 'NULL options are the defaults',
       (SELECT laban_plot(x, y, label, NULL) FROM pts) = (SELECT laban_plot(x, y, label) FROM pts)
   AND (SELECT laban_plot(x, y, label, '{}') FROM pts) = (SELECT laban_plot(x, y, label) FROM pts);

SELECT 'the same options computed on every row are fine',
       length(laban_plot(x, y, label, json_object('title', 'computed'))) > 0 FROM pts;

-- ---- errors ----
SELECT laban_plot('a', 1, 'x');
-- error: laban_plot: x (argument 1) must be a number, got text

SELECT laban_plot(1, x'00', 'x');
-- error: laban_plot: y (argument 2) must be a number, got blob

SELECT laban_plot(1, 1, x'00');
-- error: laban_plot: label (argument 3) must be text, a number or NULL, got blob

SELECT laban_plot(x, y, label) FROM (SELECT 1 AS x, 1 AS y, 'a' AS label
                                     UNION ALL SELECT 'oops', 2, 'b');
-- error: laban_plot: x (argument 1) must be a number, got text

SELECT laban_plot(NULL, 'oops', 'a');
-- error: laban_plot: y (argument 2) must be a number, got text

SELECT laban_plot(1, 1, 'a', '{"width":50}');
-- error: laban_plot: width must be between 100 and 4000, got 50

SELECT laban_plot(1, 1, 'a', '{"height":300.5}');
-- error: laban_plot: height must be a whole number, got 300.5

SELECT laban_plot(1, 1, 'a', '{"radius":0}');
-- error: laban_plot: radius must be between 0.5 and 20, got 0

SELECT laban_plot(1, 1, 'a', '{"colour":"red"}');
-- error: laban_plot: unknown option "colour" (expected title, x_label, y_label, width, height, log_x, log_y, radius, means, mode)

SELECT laban_plot(1, 1, 'a', '{"log_x":1}');
-- error: laban_plot: option "log_x" must be true or false, got number

SELECT laban_plot(1, 1, 'a', '{"title":3}');
-- error: laban_plot: option "title" must be a string, got number

SELECT laban_plot(1, 1, 'a', '{"width":"wide"}');
-- error: laban_plot: option "width" must be a number, got string

SELECT laban_plot(1, 1, 'a', '[1]');
-- error: laban_plot: options (argument 4) must be a JSON object, got array

SELECT laban_plot(1, 1, 'a', '{');
-- error: laban_plot: options (argument 4) are not valid JSON: at byte 1: unexpected end of text

SELECT laban_plot(1, 1, 'a', 42);
-- error: laban_plot: options (argument 4) must be a JSON object as text, got integer

SELECT laban_plot(x, y, label, CASE WHEN x = 1 THEN '{}' ELSE '{"title":"t"}' END) FROM pts;
-- error: laban_plot: options must be the same on every row

SELECT laban_plot(x, y, label, CASE WHEN x = 1 THEN NULL ELSE '{}' END) FROM pts;
-- error: laban_plot: options must be the same on every row

SELECT laban_plot(x, y, label, CASE WHEN x = 1 THEN '{}' ELSE 7 END) FROM pts;
-- error: laban_plot: options must be the same on every row

-- an error elsewhere in the statement stops the aggregate: its state is freed all the same
SELECT laban_plot(x, y, 'a'), sum(z)
  FROM (SELECT 1 AS x, 1 AS y, 9223372036854775807 AS z UNION ALL SELECT 2, 2, 1);
-- error: integer overflow

SELECT label, laban_plot(x, y, label) FROM (SELECT 1 AS x, 1 AS y, 'a' AS label
                                            UNION ALL SELECT 2, 2, 'b'
                                            UNION ALL SELECT 3, 'oops', 'b') GROUP BY label;
-- error: laban_plot: y (argument 2) must be a number, got text

-- =====================================================================================
-- motion_svg's animation and labels, motion_svg_group, affect_heatmap (issue 17)
-- =====================================================================================
CREATE TABLE mv(name TEXT, m BLOB);
INSERT INTO mv VALUES ('wave', motion_synth('wave', 'happy', 1)),   -- 117 frames at 30 fps
                      ('knock', motion_synth('knock', 'sad', 2)),
                      ('walk', motion_synth('walk', 'angry', 3));

SELECT group_concat(name || '/' || narg || '/' || type, ' ') FROM (
  SELECT DISTINCT name, narg, type FROM pragma_function_list
   WHERE name IN ('motion_svg_group', 'affect_heatmap') ORDER BY name, narg);
-- expect: affect_heatmap/3/a affect_heatmap/4/a motion_svg_group/2/a motion_svg_group/3/a

SELECT 'the new aggregates are deterministic and innocuous', count(*) = 4
  FROM pragma_function_list WHERE name IN ('motion_svg_group', 'affect_heatmap')
   AND (flags & 0x000000800) <> 0 AND (flags & 0x000200000) <> 0;

-- ---- motion_svg {"animate":true} ----
WITH a(svg, frames, fps) AS (SELECT motion_svg(m, '{"animate":true}'), motion_frames(m), motion_fps(m)
                               FROM mv WHERE name = 'wave')
SELECT 'an animated SVG: SMIL that loops in real time, one panel, no script',
       svg LIKE '<svg xmlns="http://www.w3.org/2000/svg"%</svg>' || char(10)
   AND instr(svg, '<animate attributeName="d"') > 0
   AND instr(svg, '<animateTransform attributeName="transform" type="translate"') > 0
   AND instr(svg, 'dur="' || printf('%g', round((frames - 1) / fps, 3)) || 's" repeatCount="indefinite"') > 0
   AND (length(svg) - length(replace(svg, '<svg x=', ''))) / 7 = 1
   AND instr(svg, '<script') = 0 AND instr(svg, 'frame 0 ·') = 0 FROM a;

-- automatic keyframes: 15 per second (117 frames at 30 fps: 1 + ceil(116 / 30 × 15) = 59)
WITH a(v) AS (SELECT substr(svg, instr(svg, 'values="') + 8) FROM
               (SELECT substr(s, instr(s, '<animate attributeName="d"')) AS svg
                  FROM (SELECT motion_svg(m, '{"animate":true}') AS s FROM mv WHERE name = 'wave')))
SELECT 'automatic keyframes', length(substr(v, 1, instr(v, '"') - 1))
         - length(replace(substr(v, 1, instr(v, '"') - 1), ';', '')) + 1 = 59 FROM a;

WITH a(v) AS (SELECT substr(svg, instr(svg, 'values="') + 8) FROM
               (SELECT substr(s, instr(s, '<animate attributeName="d"')) AS svg
                  FROM (SELECT motion_svg(m, '{"animate":true,"keyframes":7}') AS s FROM mv WHERE name = 'wave')))
SELECT 'keyframes as asked', length(substr(v, 1, instr(v, '"') - 1))
         - length(replace(substr(v, 1, instr(v, '"') - 1), ';', '')) + 1 = 7 FROM a;

SELECT 'the film strip stays the default; animations are deterministic',
       motion_svg(m) = motion_svg(m, '{"animate":false}')
   AND instr(motion_svg(m), '<animate') = 0
   AND motion_svg(m, '{"animate":true,"view":"top"}') = motion_svg(m, '{"animate":true,"view":"top"}')
  FROM mv WHERE name = 'walk';

SELECT 'the top view turns the walk and marks where the body faces',
       instr(motion_svg(m, '{"view":"top"}'), 'class="facing"') > 0
   AND instr(motion_svg(m, '{"view":"top","animate":true}'), '<animate attributeName="points"') > 0
  FROM mv WHERE name = 'walk';

SELECT 'labels "state": state N under panel N (hmm_postures)',
       instr(motion_svg(motion_slice(m, 0, 3), '{"labels":"state"}'), '>state 3</text>') > 0
   AND instr(motion_svg(motion_slice(m, 0, 3), '{"labels":"state"}'), 'frame ') = 0
   AND motion_svg(m, '{"labels":"frame"}') = motion_svg(m, '{"labels":true}')
  FROM mv WHERE name = 'knock';

SELECT 'NULL in, NULL out', motion_svg(NULL, '{"animate":true}') IS NULL;

SELECT motion_svg(m, '{"animate":true,"keyframes":1}') FROM mv WHERE name = 'wave';
-- error: motion_svg: keyframes must be 0 (automatic) or between 2 and 1000, got 1

SELECT motion_svg(m, '{"animate":true,"keyframes":2.5}') FROM mv WHERE name = 'wave';
-- error: motion_svg: options "frames", "size" and "keyframes" must be whole numbers

SELECT motion_svg(m, '{"animate":true,"frames":4}') FROM mv WHERE name = 'wave';
-- error: motion_svg: option "frames" is for the film strip (an animation takes "keyframes")

SELECT motion_svg(m, '{"keyframes":4}') FROM mv WHERE name = 'wave';
-- error: motion_svg: option "keyframes" needs "animate":true

SELECT motion_svg(m, '{"animate":"yes"}') FROM mv WHERE name = 'wave';
-- error: motion_svg: option "animate" must be true or false, got string

SELECT motion_svg(m, '{"labels":"time"}') FROM mv WHERE name = 'wave';
-- error: motion_svg: option "labels" must be one of "frame", "state", got "time"

SELECT motion_svg(m, '{"labels":null}') FROM mv WHERE name = 'wave';
-- error: motion_svg: option "labels" must be true, false, "frame" or "state", got null

SELECT motion_svg(m, '{"animte":true}') FROM mv WHERE name = 'wave';
-- error: motion_svg: unknown option "animte" (expected view, frames, size, up, trajectories, labels, title, animate, keyframes, roles)

-- ---- motion_svg_group ----
WITH g(svg) AS (SELECT motion_svg_group(m, name, '{"animate":true,"size":100}')
                  FROM (SELECT * FROM mv ORDER BY name))
SELECT 'animated side by side, in row order, with captions',
       svg LIKE '<svg xmlns="http://www.w3.org/2000/svg" width="300" %</svg>' || char(10)
   AND (length(svg) - length(replace(svg, '<svg x=', ''))) / 7 = 3
   AND instr(svg, '>knock</text>') < instr(svg, '>walk</text>')
   AND instr(svg, '>walk</text>') < instr(svg, '>wave</text>')
   AND (length(svg) - length(replace(svg, 'repeatCount="indefinite"', ''))) > 3 FROM g;

WITH g(svg) AS (SELECT motion_svg_group(m, name, '{"frames":3}') FROM mv)
SELECT 'strips: one per row, with its caption above',
       (length(svg) - length(replace(svg, '<svg x=', ''))) / 7 = 9
   AND (length(svg) - length(replace(svg, 'class="caption"', ''))) / 15 = 3
   AND instr(svg, '<animate') = 0 FROM g;

SELECT 'a group of one without caption is motion_svg',
       (SELECT motion_svg_group(m, NULL) FROM mv WHERE name = 'wave')
       = (SELECT motion_svg(m) FROM mv WHERE name = 'wave')
   AND (SELECT motion_svg_group(m, NULL, '{"animate":true}') FROM mv WHERE name = 'wave')
       = (SELECT motion_svg(m, '{"animate":true}') FROM mv WHERE name = 'wave');

SELECT 'NULL motions are skipped; none at all gives NULL',
       (SELECT motion_svg_group(NULL, 'x')) IS NULL
   AND (SELECT motion_svg_group(m, name) FROM mv WHERE 0) IS NULL
   AND (SELECT motion_svg_group(CASE WHEN name = 'wave' THEN m END, name) FROM mv)
       = (SELECT motion_svg_group(m, name) FROM mv WHERE name = 'wave');

SELECT 'a number caption is text', instr(motion_svg_group(m, 42), '>42</text>') > 0
  FROM mv WHERE name = 'wave';

SELECT motion_svg_group(m, x'00') FROM mv;
-- error: motion_svg_group: caption (argument 2) must be text, a number or NULL, got blob

SELECT motion_svg_group(m, name, CASE name WHEN 'wave' THEN '{}' ELSE '{"animate":true}' END)
  FROM (SELECT * FROM mv ORDER BY name);
-- error: motion_svg_group: options must be the same on every row

SELECT motion_svg_group('walk', 'a');
-- error: motion_svg_group: argument 1 must be a motion BLOB, got text

SELECT motion_svg_group(m, name, '{"animate":true,"frames":3}') FROM mv;
-- error: motion_svg_group: option "frames" is for the film strip (an animation takes "keyframes")

WITH RECURSIVE k(i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM k WHERE i < 65)
SELECT motion_svg_group(m, i) FROM k, mv WHERE mv.name = 'knock';
-- error: motion_svg_group: at most 64 motions in a group

-- ---- affect_heatmap ----
CREATE TABLE cells(r, c, v);
INSERT INTO cells VALUES ('sad · state 1', 'Head', 0.5), ('sad · state 1', 'Hand_L', 1),
                         ('sad · state 2', 'Head', 0.25), ('sad · state 2', 'Head', 0.75),
                         ('angry <1>', 'Foot_R', 0), (NULL, 'Head', 1), ('x', NULL, 1),
                         ('y', 'Head', NULL);

WITH h(svg) AS (SELECT affect_heatmap(r, c, v, '{"title":"salience","cell":30}') FROM cells)
SELECT 'joint names on the axes, not only in tooltips',
       svg LIKE '<svg xmlns="http://www.w3.org/2000/svg"%</svg>' || char(10)
   AND (length(svg) - length(replace(svg, '<text class="row-label"', ''))) / 23 = 3
   AND (length(svg) - length(replace(svg, '<text class="column-label"', ''))) / 26 = 3
   AND instr(svg, 'rotate(-45)">Hand_L</text>') > 0
   AND instr(svg, '>angry &lt;1&gt;</text>') > 0
   AND instr(svg, '<title>sad · state 2 × Head: 0.75</title>') > 0   -- a repeated cell: the larger
   AND (length(svg) - length(replace(svg, '<rect class="cell"', ''))) / 18 = 9
   AND instr(svg, '>salience</text>') > 0 FROM h;

SELECT 'sorted rows and columns',
       instr(svg, '>Foot_R</text>') < instr(svg, '>Hand_L</text>')
   AND instr(svg, '>Hand_L</text>') < instr(svg, '>Head</text>')
   AND instr(svg, '>angry &lt;1&gt;</text>') < instr(svg, '>sad · state 1</text>')
  FROM (SELECT affect_heatmap(r, c, v, '{"sort_rows":true,"sort_columns":true}') AS svg
          FROM (SELECT * FROM cells ORDER BY v DESC));

SELECT 'no rows: the empty map', instr(affect_heatmap(r, c, v), '>no data</text>') > 0
  FROM cells WHERE 0;

SELECT 'values printed when asked',
       instr(affect_heatmap(r, c, v, '{"values":true}'), 'class="value"') > 0
   AND instr(affect_heatmap(r, c, v, '{"values":false,"cell":60}'), 'class="value"') = 0 FROM cells;

SELECT affect_heatmap(r, c, 'high') FROM cells;
-- error: affect_heatmap: value (argument 3) must be a number, got text

SELECT affect_heatmap(x'01', 'c', 1);
-- error: affect_heatmap: row (argument 1) must be text or a number, got blob

SELECT affect_heatmap(r, c, v, '{"cell":4}') FROM cells;
-- error: affect_heatmap: cell must be between 8 and 120, got 4

SELECT affect_heatmap(r, c, v, '{"min":1,"max":1}') FROM cells;
-- error: affect_heatmap: min must be below max, got 1 and 1

SELECT affect_heatmap(r, c, v, '{"colours":"viridis"}') FROM cells;
-- error: affect_heatmap: unknown option "colours" (expected title, x_label, y_label, cell, values, min, max, sort_rows, sort_columns)

WITH RECURSIVE k(i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM k WHERE i < 1001)
SELECT affect_heatmap('r', 'c' || i, i) FROM k;
-- error: affect_heatmap: more than 1000 columns
