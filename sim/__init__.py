"""MuJoCo worlds shipped with motion2robot (installed as the resource package motion2robot.worlds)."""
