"""The team's protocol below any transport, written once with the clock passed in: the centre's rounds
(:mod:`~mrexplore.team.rounds`), each robot's goals, routes and blacklists (:mod:`~mrexplore.team.goal_book`)
and a navigation stack's goals as its action status reports them (:mod:`~mrexplore.team.nav_goals`). The
simulator drives these objects on a clock in steps or rounds, the ROS 2 nodes on one in seconds."""
