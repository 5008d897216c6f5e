"""legged_gente: legged locomotion over generated, physically realistic terrains."""
