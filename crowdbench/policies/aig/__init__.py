"""AIG-GST (Liu et al. 2023): the attention-graph baseline with a trajectory predictor (see :mod:`.model`)."""
