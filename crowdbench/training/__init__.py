"""Training: the rsl-rl VecEnv over batched crowd worlds, the curriculum and the H²INT trainer."""
