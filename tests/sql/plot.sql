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
