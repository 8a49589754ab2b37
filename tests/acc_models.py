"""Model texts several test modules share: loops nobody tuned for lyapcheck (issue 40's new-user runs)."""

#: an ACC whose initial set (closing in at 10 m/s from 10-12 m) runs into the unsafe gap h <= 5 m,
#: while its equilibrium (h = 30 m, v = vL) is globally exponentially stable
UNSAFE_ACC = """
[model]
name = "adaptive cruise control that is unsafe"
states = ["h", "v"]

[units]
h = "m"
v = "m/s"

[parameters]
vL = "20 m/s"
kp = "0.2 1/s^2"
kd = "0.5 1/s"
h0 = "30 m"
h_lo = "10 m"
h_hi = "12 m"
v_lo = "30 m/s"
v_hi = "32 m/s"
hmin = "5 m"

[dynamics]
h = "vL - v"
v = "kp*(h - h0) + kd*(vL - v)"

[equilibrium]
h = "30 m"
v = "20 m/s"

[domain]
h = ["0 m", "60 m"]
v = ["0 m/s", "40 m/s"]

[sets]
initial = ["h_lo <= h", "h <= h_hi", "v_lo <= v", "v <= v_hi"]
unsafe = ["h <= hmin"]
"""
