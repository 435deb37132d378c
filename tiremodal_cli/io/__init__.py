"""Files at the edges: atomic writes and checksums, measurements, FRF and modal files, option files, ingest of UFF/CSV records, shapes out."""
