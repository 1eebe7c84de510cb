"""DS-RNN (Liu et al. 2021): the graph-recurrent baseline of the paper's tables (see :mod:`.model`)."""
