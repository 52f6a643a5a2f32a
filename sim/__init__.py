"""Physics of mechopt: mechanisms, kinematics, feasibility, motion laws, analytic dynamics, pymunk simulation."""
