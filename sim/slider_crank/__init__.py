"""The slider-crank mechanism O-A-B: kinematics, feasibility margins, analytic and pymunk engines, and the studies
of papers 001 (offset crank-slider, stroke and time ratio) and 003 (rowing machine, spring effort)."""
