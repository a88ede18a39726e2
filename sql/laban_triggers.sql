-- laban_triggers.sql — keeps a laban index current with its content table: every insert,
-- update and delete on motions issues the matching command on motion_laban.
--
--   sqlite3 demo.db -cmd '.load ./build/affect' < sql/laban_triggers.sql
--
-- A template: it assumes sql/schema.sql's motions table and an index created as
--   CREATE VIRTUAL TABLE motion_laban USING laban(content=motions, motion=motion, label=emotion);
-- For other names, replace motions and motion_laban below (the index's name is also the name
-- of its command column). 'refresh' recomputes a row's descriptors only when its motion's bytes
-- changed (a label or name change costs one hash), and removes the row when the motion became
-- NULL; the index's mean and sd are recomputed once per transaction, so a bulk insert inside
-- BEGIN … COMMIT stays fast. The laban table may be used from triggers only while
-- PRAGMA trusted_schema is ON (SQLite's default).
CREATE TRIGGER IF NOT EXISTS motions_laban_insert AFTER INSERT ON motions BEGIN
    INSERT INTO motion_laban(motion_laban, rowid) VALUES('refresh', new.rowid);
END;

CREATE TRIGGER IF NOT EXISTS motions_laban_update AFTER UPDATE ON motions BEGIN
    INSERT INTO motion_laban(motion_laban, rowid)
    SELECT 'delete', old.rowid WHERE old.rowid IS NOT new.rowid;
    INSERT INTO motion_laban(motion_laban, rowid) VALUES('refresh', new.rowid);
END;

CREATE TRIGGER IF NOT EXISTS motions_laban_delete AFTER DELETE ON motions BEGIN
    INSERT INTO motion_laban(motion_laban, rowid) VALUES('delete', old.rowid);
END;
