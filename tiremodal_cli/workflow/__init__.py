"""The whole loop: run, batch over folders, the report."""
