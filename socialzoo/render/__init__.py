"""Drawing: map pictures, env frames and animations (matplotlib, Pillow and imageio, imported lazily)."""
