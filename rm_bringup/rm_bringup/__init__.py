"""rm_bringup: robot configs, launch files, runner, command-line tool and bags."""
