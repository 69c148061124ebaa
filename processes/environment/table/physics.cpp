#include "environment/table/physics.hpp"

#include <cmath>
#include <cstring>
#include <string>
#include <stdexcept>

namespace afford::table {

namespace {

// MuJoCo reads a model from files; the MJCF text is handed to it as the one file of a virtual file system.
mjModel* loadFromText(const std::string& mjcf) {
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const char* name = "afford-table.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), name, static_cast<int>(mjcf.size())) != 0)
    throw std::runtime_error("MuJoCo: cannot hold the table's model in memory");
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), name)], mjcf.data(), mjcf.size());
  char error[1024] = "";
  mjModel* m = mj_loadXML(name, vfs.get(), error, sizeof error);
  mj_deleteVFS(vfs.get());
  if (!m) throw std::runtime_error(std::string("MuJoCo refused the table's model: ") + error);
  return m;
}

int idOf(const mjModel* m, mjtObj type, const std::string& name) {
  const int id = mj_name2id(m, type, name.c_str());
  if (id < 0) throw std::runtime_error("the table's model has no '" + name + "'");
  return id;
}

}  // namespace

TablePhysics::TablePhysics(const TableSpec& spec) : spec_(spec) {
  model_ = loadFromText(tableMjcf(spec_));
  data_ = mj_makeData(model_);
  if (!data_) {
    mj_deleteModel(model_);
    throw std::runtime_error("MuJoCo: cannot allocate the table's simulation data");
  }
  geom_object_.assign(static_cast<std::size_t>(model_->ngeom), -1);
  for (const ObjectSpec& o : spec_.objects) {
    const int body = idOf(model_, mjOBJ_BODY, o.name);
    const int joint = idOf(model_, mjOBJ_JOINT, o.name);
    object_body_.push_back(body);
    object_qpos_.push_back(model_->jnt_qposadr[joint]);
    object_dof_.push_back(model_->jnt_dofadr[joint]);
    geom_object_[static_cast<std::size_t>(idOf(model_, mjOBJ_GEOM, o.name))] = static_cast<int>(object_body_.size()) - 1;
  }
  hand_body_ = idOf(model_, mjOBJ_BODY, "hand");
  const char* actuators[] = {"hand_x", "hand_y", "hand_z", "hand_yaw", "hand_finger_l", "hand_finger_r"};
  for (std::size_t i = 0; i < actuator_.size(); ++i) actuator_[i] = idOf(model_, mjOBJ_ACTUATOR, actuators[i]);
  for (std::size_t i = 0; i < hand_qpos_.size(); ++i)
    hand_qpos_[i] = model_->jnt_qposadr[idOf(model_, mjOBJ_JOINT, actuators[i])];
  // The hand waits at its parking place, open.
  const HandSpec& h = spec_.hand;
  data_->qpos[hand_qpos_[0]] = h.park[0];
  data_->qpos[hand_qpos_[1]] = h.park[1];
  data_->qpos[hand_qpos_[2]] = h.park[2] - h.rest_height;
  commandHand({h.park[0], h.park[1], h.park[2], 0, 1});
  mj_forward(model_, data_);
}

TablePhysics::~TablePhysics() {
  mj_deleteData(data_);
  mj_deleteModel(model_);
}

void TablePhysics::step(int n) {
  for (int i = 0; i < n; ++i) {
    mj_step(model_, data_);
    if (observer_ && ++observed_ % observe_every_ == 0) observer_();
  }
}

void TablePhysics::observe(std::function<void()> f, int every) {
  if (every < 1) throw std::invalid_argument("TablePhysics::observe: every " + std::to_string(every) + " (at least 1)");
  observer_ = std::move(f);
  observe_every_ = every;
  observed_ = 0;
}

Pose TablePhysics::objectPose(int i) const {
  Pose p;
  const mjtNum* q = data_->qpos + object_qpos_.at(static_cast<std::size_t>(i));
  for (int k = 0; k < 3; ++k) p.pos[static_cast<std::size_t>(k)] = q[k];
  for (int k = 0; k < 4; ++k) p.quat[static_cast<std::size_t>(k)] = q[3 + k];
  return p;
}

void TablePhysics::placeObject(int i, double x, double y, double yaw) {
  const ObjectSpec& o = spec_.objects.at(static_cast<std::size_t>(i));
  mjtNum* q = data_->qpos + object_qpos_[static_cast<std::size_t>(i)];
  q[0] = x;
  q[1] = y;
  q[2] = o.restingHeight();
  // A turn by yaw about z (the lying cylinder's own turn is in its geom's frame, so a body turn keeps it lying).
  q[3] = std::cos(yaw / 2);
  q[4] = 0;
  q[5] = 0;
  q[6] = std::sin(yaw / 2);
  mjtNum* v = data_->qvel + object_dof_[static_cast<std::size_t>(i)];
  for (int k = 0; k < 6; ++k) v[k] = 0;
  forward();
}

void TablePhysics::commandHand(const HandCommand& c) {
  // The hand's joints are relative to its body's place: over the table's centre at rest_height.
  data_->ctrl[actuator_[0]] = c.x;
  data_->ctrl[actuator_[1]] = c.y;
  data_->ctrl[actuator_[2]] = c.z - spec_.hand.rest_height;
  data_->ctrl[actuator_[3]] = c.yaw;
  const double open = std::min(1.0, std::max(0.0, c.opening));
  const double closed = -(spec_.hand.finger_travel - spec_.hand.finger_half[1]);
  data_->ctrl[actuator_[4]] = data_->ctrl[actuator_[5]] = (1 - open) * closed;
}

int TablePhysics::instabilities() const { return data_->warning[mjWARN_BADQACC].number; }

HandCommand TablePhysics::handNow() const {
  HandCommand h;
  h.x = data_->qpos[hand_qpos_[0]];
  h.y = data_->qpos[hand_qpos_[1]];
  h.z = data_->qpos[hand_qpos_[2]] + spec_.hand.rest_height;
  h.yaw = data_->qpos[hand_qpos_[3]];
  const double closed = -(spec_.hand.finger_travel - spec_.hand.finger_half[1]);
  const int finger = model_->jnt_qposadr[model_->actuator_trnid[2 * actuator_[4]]];
  h.opening = 1 - data_->qpos[finger] / closed;
  return h;
}

bool TablePhysics::atRest(double linear, double angular) const {
  for (std::size_t i = 0; i < object_dof_.size(); ++i) {
    const mjtNum* v = data_->qvel + object_dof_[i];
    if (std::hypot(v[0], v[1], v[2]) > linear || std::hypot(v[3], v[4], v[5]) > angular) return false;
  }
  for (int j = 0; j < model_->njnt; ++j) {
    if (model_->jnt_bodyid[j] == hand_body_ || model_->body_parentid[model_->jnt_bodyid[j]] == hand_body_) {
      const double v = std::abs(data_->qvel[model_->jnt_dofadr[j]]);
      if (v > (model_->jnt_type[j] == mjJNT_HINGE ? angular : linear)) return false;
    }
  }
  return true;
}

int TablePhysics::objectOfGeom(int geom) const {
  return geom >= 0 && geom < static_cast<int>(geom_object_.size()) ? geom_object_[static_cast<std::size_t>(geom)] : -1;
}

std::vector<double> TablePhysics::state() const {
  const mjModel* m = model_;
  std::vector<double> s;
  s.reserve(static_cast<std::size_t>(1 + m->nq + 2 * m->nv + m->na + m->nu));
  s.push_back(data_->time);
  s.insert(s.end(), data_->qpos, data_->qpos + m->nq);
  s.insert(s.end(), data_->qvel, data_->qvel + m->nv);
  s.insert(s.end(), data_->act, data_->act + m->na);
  s.insert(s.end(), data_->ctrl, data_->ctrl + m->nu);
  s.insert(s.end(), data_->qacc_warmstart, data_->qacc_warmstart + m->nv);
  return s;
}

void TablePhysics::setState(const std::vector<double>& s) {
  const mjModel* m = model_;
  const std::size_t want = static_cast<std::size_t>(1 + m->nq + 2 * m->nv + m->na + m->nu);
  if (s.size() != want)
    throw std::invalid_argument("a table state of " + std::to_string(s.size()) + " values, and this table's has " +
                                std::to_string(want) + " (another world's configuration?)");
  const double* p = s.data();
  data_->time = *p++;
  std::copy(p, p + m->nq, data_->qpos), p += m->nq;
  std::copy(p, p + m->nv, data_->qvel), p += m->nv;
  std::copy(p, p + m->na, data_->act), p += m->na;
  std::copy(p, p + m->nu, data_->ctrl), p += m->nu;
  std::copy(p, p + m->nv, data_->qacc_warmstart);
  forward();
}

void TablePhysics::forward() {
  // MuJoCo's forward pass also writes the solver's warm start and normalises the free bodies' quaternions in
  // place (a quaternion normalised twice can differ in its last bit from one normalised once): both are put
  // back, so that the next step is the one it would have been without the pass, and a state saved after it and
  // set again goes on bit for bit.
  const std::vector<double> warm(data_->qacc_warmstart, data_->qacc_warmstart + model_->nv);
  const std::vector<double> qpos(data_->qpos, data_->qpos + model_->nq);
  mj_forward(model_, data_);
  std::copy(warm.begin(), warm.end(), data_->qacc_warmstart);
  std::copy(qpos.begin(), qpos.end(), data_->qpos);
}

}  // namespace afford::table
