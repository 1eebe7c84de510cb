"""H²INT's private kernels: the packed-token encoder and what it is built from (ragged attention, the fused GTrXL gate,
oneDNN linear products). Not an API: :meth:`crowdbench.policies.h2int.model.H2INTEncoder.packed` is the entry point,
tested equal to the eager reference."""
