-- quickstart.sql — the motion functions from the sqlite3 shell.
--
--   sqlite3 -cmd '.load ./build/affect' < examples/quickstart.sql
.headers on
.mode column
SELECT affect_version() AS version;

-- a synthetic sad and angry wave of the same performer
CREATE TEMP TABLE m AS
SELECT 'sad' AS emotion, motion_synth('wave', 'sad', 7) AS motion
UNION ALL SELECT 'angry', motion_synth('wave', 'angry', 7);

SELECT emotion, motion_frames(motion) AS frames, motion_joints(motion) AS joints,
       printf('%.2f', motion_duration(motion)) AS seconds FROM m;

-- where is the right hand highest, and how fast does it get there?
SELECT emotion, printf('%.3f', max(p.y)) AS top_of_hand_m, min(p.frame) AS first_frame_at_top
  FROM m, motion_points(m.motion) AS p
 WHERE p.name = 'Hand_R'
   AND p.y >= (SELECT max(q.y) - 0.005 FROM motion_points(m.motion) AS q WHERE q.name = 'Hand_R')
 GROUP BY emotion;

-- editing: the first second, at 10 fps, hands only
SELECT emotion, motion_info(motion_select(motion_resample(motion_slice(motion, 0, 29), 10),
                                          '["Hand_L","Hand_R"]')) AS info
  FROM m WHERE emotion = 'sad';

-- normalization: start at the origin facing +z, in units of the right arm's length
SELECT emotion, json_extract(motion_to_json(motion_normalize(motion, '{"scale":"arm"}')),
                             '$.frames[0][0]') AS pelvis_at_start
  FROM m;
