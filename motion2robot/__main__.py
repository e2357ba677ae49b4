from motion2robot.cli import run

run()
