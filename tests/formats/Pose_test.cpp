// Poses: the rotation matrix against Eigen's quaternion (an independent implementation), the
// canonical apply_pose, and pose files (round trip, bad lines).

#include <Eigen/Geometry>

#include "TestSupport.h"
#include "tetrapage/formats/mesh/Pose.h"

namespace tetrapage::test {
namespace {

std::array<double, 4> random_unit_quaternion(Random& random) {
  std::array<double, 4> q;
  double norm = 0;
  do {
    norm = 0;
    for (double& c : q) {
      c = random.normal();
      norm += c * c;
    }
  } while (norm < 1e-6);
  norm = std::sqrt(norm);
  for (double& c : q) c /= norm;
  return q;
}

TEST(Pose, RotationMatrixMatchesEigenAndIsOrthonormal) {
  Random random(4242);
  for (int trial = 0; trial < 1000; ++trial) {
    const auto q = random_unit_quaternion(random);
    const auto r = rotation_matrix(q);
    const Eigen::Matrix3d expected = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).toRotationMatrix();
    for (int row = 0; row < 3; ++row) {
      for (int column = 0; column < 3; ++column) {
        ASSERT_NEAR(r[3 * row + column], expected(row, column), 1e-15)
            << "seed 4242 trial " << trial << " entry " << row << "," << column;
      }
    }
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> m(r.data());
    ASSERT_TRUE((m * m.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-14));
    ASSERT_NEAR(m.determinant(), 1.0, 1e-14);
  }
}

TEST(Pose, ANearlyUnitQuaternionGivesTheUnitOnesMatrix) {
  // A caller's q may be off unit norm (a float's rounding, up to 1e-6 in its square): its
  // matrix is the unit q's, orthonormal, not a stretched one; a unit q is kept bit for bit.
  Random random(777);
  for (int trial = 0; trial < 1000; ++trial) {
    const auto q = random_unit_quaternion(random);
    EXPECT_EQ(unit_quaternion(q), q);
    auto stretched = q;
    const double scale = trial % 2 == 0 ? 1 + 4e-7 : 1 - 4e-7;
    for (double& c : stretched) c *= scale;
    const auto r = rotation_matrix(stretched);
    const auto expected = rotation_matrix(q);
    for (int k = 0; k < 9; ++k) ASSERT_NEAR(r[k], expected[k], 4e-15) << "seed 777 trial " << trial;
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> m(r.data());
    ASSERT_TRUE((m * m.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-14)) << "trial " << trial;
  }
}

TEST(Pose, ApplyPoseIsRotationThenTranslation) {
  Random random(99);
  for (int trial = 0; trial < 1000; ++trial) {
    Pose pose;
    pose.rotation = random_unit_quaternion(random);
    pose.translation = {random.uniform(-100, 100), random.uniform(-100, 100),
                        random.uniform(-100, 100)};
    const Vec3 x{random.uniform(-10, 10), random.uniform(-10, 10), random.uniform(-10, 10)};
    const Eigen::Vector3d expected =
        Eigen::Quaterniond(pose.rotation[0], pose.rotation[1], pose.rotation[2], pose.rotation[3]) *
            Eigen::Vector3d(x[0], x[1], x[2]) +
        Eigen::Vector3d(pose.translation[0], pose.translation[1], pose.translation[2]);
    const Vec3 world = apply_pose(pose, x);
    for (int k = 0; k < 3; ++k)
      ASSERT_NEAR(world[k], expected[k], 1e-12) << "seed 99 trial " << trial;
  }
  // The identity and pure translations are exact.
  const Vec3 x{0.1, -1e300, 7e-300};
  EXPECT_EQ(apply_pose(Pose{}, x), x);
  Pose shifted;
  shifted.translation = {1, 2, 3};
  EXPECT_EQ(apply_pose(shifted, Vec3{0.5, 0.25, -0.125}), (Vec3{1.5, 2.25, 2.875}));
}

TEST(PoseFile, RoundTripIsBitExact) {
  const auto folder = scratch_folder("poses_round_trip");
  Random random(7);
  std::vector<Pose> poses(500);
  for (auto& pose : poses) {
    pose.rotation = random_unit_quaternion(random);
    for (double& t : pose.translation)
      t = random.normal() * std::pow(10.0, random.uniform(-12, 12));
  }
  poses[0] = Pose{};
  poses[1].translation = {-0.0, 1e-320, -1.7976931348623157e308};  // sign of zero, subnormal, max
  const auto path = folder / "flight.csv";
  write_poses(path, poses);
  EXPECT_EQ(folder_listing(folder), std::vector<std::string>{"flight.csv"});
  const auto back = read_poses(path);
  ASSERT_EQ(back.size(), poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(std::bit_cast<std::uint64_t>(back[i].translation[k]),
                std::bit_cast<std::uint64_t>(poses[i].translation[k]))
          << "seed 7 pose " << i;
    }
    EXPECT_EQ(back[i].rotation, poses[i].rotation) << "seed 7 pose " << i;
  }
  EXPECT_TRUE(read_file(path).starts_with("tx,ty,tz,qw,qx,qy,qz\n"));
}

// A rotation whose squared length is within kUnitQuaternionTolerance of 1 (as printed digits leave it)
// is normalised; one further off is refused, as the C API and Python refuse it.
TEST(PoseFile, QuaternionsAreNormalisedOnRead) {
  const auto folder = scratch_folder("poses_normalise");
  const auto path = folder / "p.csv";
  write_file(path, "tx,ty,tz,qw,qx,qy,qz\r\n1,2,3,1.0000004,0,0,0\r\n\r\n 0 , 0 , 0 , 0.5000002 , 0.5 , 0.5 , 0.5 \n");
  const auto poses = read_poses(path);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[0].translation, (Vec3{1, 2, 3}));
  EXPECT_EQ(poses[0].rotation, (std::array<double, 4>{1, 0, 0, 0}));
  double length = 0;
  for (const double q : poses[1].rotation) length += q * q;
  EXPECT_NEAR(length, 1.0, 1e-15);
  EXPECT_NEAR(poses[1].rotation[0], 0.5, 1e-6);
  write_file(path, "tx,ty,tz,qw,qx,qy,qz\n1,2,3,2,0,0,0\n");
  EXPECT_THROW(read_poses(path), InputError);
}

TEST(PoseFile, BadFilesNameLineAndValue) {
  const auto folder = scratch_folder("poses_bad");
  const auto path = folder / "bad.csv";
  const std::string header = "tx,ty,tz,qw,qx,qy,qz\n";
  write_file(path, "tx,ty,tz,qx,qw,qy,qz\n0,0,0,1,0,0,0\n");
  expect_error<FormatError>([&] { read_poses(path); }, {path.string(), "line 1", "header"});
  write_file(path, "");
  expect_error<FormatError>([&] { read_poses(path); }, {path.string(), "header"});
  write_file(path, header + "0,0,0,1,0,0,0\n0,0,0,1,0,0\n");
  expect_error<FormatError>([&] { read_poses(path); }, {path.string(), "line 3", "got 6"});
  write_file(path, header + "0,0,0,1,0,0,0,5\n");
  expect_error<FormatError>([&] { read_poses(path); }, {path.string(), "line 2", "got 8"});
  write_file(path, header + "0,0,0,1,0,0,0\n0,abc,0,1,0,0,0\n");
  expect_error<FormatError>([&] { read_poses(path); }, {path.string(), "line 3", "ty", "'abc'"});
  write_file(path, header + "0,0,nan,1,0,0,0\n");
  expect_error<InputError>([&] { read_poses(path); }, {path.string(), "line 2", "tz", "'nan'"});
  write_file(path, header + "0,0,0,1,0,inf,0\n");
  expect_error<InputError>([&] { read_poses(path); }, {path.string(), "line 2", "qy", "'inf'"});
  write_file(path, header + "0,0,0,0,0,0,0\n");
  expect_error<InputError>([&] { read_poses(path); }, {path.string(), "line 2", "quaternion"});
  write_file(path, header + "0,0,0,1,0,,0\n");
  expect_error<FormatError>([&] { read_poses(path); }, {path.string(), "line 2", "qy"});
  expect_error<IoError>([&] { read_poses(folder / "none.csv"); }, {"none.csv"});
  expect_error<IoError>([&] { write_poses(folder / "missing" / "p.csv", {}); }, {"p.csv"});
}

}  // namespace
}  // namespace tetrapage::test
