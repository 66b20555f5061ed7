"""The run record: the format of a run directory (its CSV tables, robot file and summary), the writer and readers
of it, the compiled row formatter, and the summary models — below the analysis, the interop and the run loop, which
all read or write runs."""
