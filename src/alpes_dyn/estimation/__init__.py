"""The estimation floor: observers (EKF, UKF), recordings, identification experiments, the fit and
the estimation scenario."""
