"""Studies: single experiments composed from the harness (socialzoo.bench) and the trainers (socialzoo.train),
each with its own tables and figures; `socialzoo reproduce` and the command line call them."""
