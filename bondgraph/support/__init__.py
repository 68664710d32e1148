"""What every stage uses: typed errors (:mod:`.errors`), the settings table (:mod:`.config`),
progress reports (:mod:`.progress`), clean interruption (:mod:`.interrupt`) and atomic
output files (:mod:`.atomic`).  Nothing here knows of bond graphs."""
