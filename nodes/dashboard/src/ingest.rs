//! DDS side: every published topic is read raw (a queue of 200, of 5 for bulk types such as
//! images), reliably when every publisher discovered offers reliable, best effort otherwise (as
//! the recorder adapts, `recording_qos`): RustDDS (0.15) never counts a best-effort reader's
//! samples as acknowledged, so a reliable writer matched by one keeps its last 8192 samples, and
//! a dashboard reading everything best effort made every node's writers grow to that. Bulk
//! topics stay best effort (their writers bound their history themselves). Forwarded as CDR
//! to the Foxglove server and, when it has a role, decoded into the dashboard state. Discovery is rescanned every second, so sensors that
//! appear late (a new `temperature/<sensor>`) show up too.

use std::collections::BTreeSet;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use metrocell_bagtools::recorded_qos::{offered_qos_of_topic, recording_qos};
use metrocell_bagtools::SourcedMessage;
use metrocell_dashboard_state::DashboardState;
use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint, TrackerMeasurement};
use metrocell_msgs::rosgraph_msgs::msg::Clock;
use metrocell_msgs::sensor_msgs::msg::Temperature;
use metrocell_msgs::RosMessage;
use metrocell_node::names::dds_topic_name;
use metrocell_node::{qos, MetrocellNode, RawMessage, RawSubscription};

use crate::foxglove_bridge::FoxgloveBridge;
use crate::routes::{Role, Routes};

/// Queue of a bulk topic (images): the newest few frames, for the Foxglove bridge.
const BULK_DEPTH: usize = 5;

pub struct Ingest {
    routes: Routes,
    subscriptions: Vec<(RawSubscription, Role)>,
    known: BTreeSet<String>,
    next_scan: Instant,
}

impl Ingest {
    pub fn new(routes: Routes) -> Ingest {
        Ingest {
            routes,
            subscriptions: Vec::new(),
            known: BTreeSet::new(),
            next_scan: Instant::now(),
        }
    }

    /// Subscribe topics that appeared since the last scan (at most once a second).
    pub fn scan(
        &mut self,
        node: &mut MetrocellNode,
        bridge: Option<&mut FoxgloveBridge>,
    ) -> Result<(), Box<dyn std::error::Error>> {
        if Instant::now() < self.next_scan {
            return Ok(());
        }
        self.next_scan = Instant::now() + Duration::from_secs(1);
        let mut bridge = bridge;
        // The writers' offered QoS, copied from discovery once per scan that finds a new topic.
        let mut writers = None;
        for t in node.discovered_publications() {
            if !self.known.insert(t.name.clone()) {
                continue;
            }
            let Ok(definition) = metrocell_msgs::registry().full_definition(&t.type_name) else {
                node.info(format!(
                    "not showing {}: metrocell does not know its type {}",
                    t.name, t.type_name
                ));
                continue;
            };
            // camera frames are only forwarded (to Foxglove): a few, not 200 of them (≈ 1 GB of
            // 5 MP frames; RustDDS keeps a reader's whole queue), and no more than those
            let sub = if metrocell_bagtools::is_bulk_type(&t.type_name) {
                node.bounded_raw_subscription(
                    &t.name,
                    &t.type_name,
                    qos::sensor_data()
                        .history(ros2_client::qos::History::KeepLast { depth: BULK_DEPTH }),
                )?
            } else {
                let writers = writers.get_or_insert_with(|| {
                    node.context().domain_participant().discovered_writers()
                });
                let offered = offered_qos_of_topic(
                    writers.iter().map(|w| &w.publication_topic_data),
                    &dds_topic_name(&t.name),
                );
                let profile = if recording_qos(&offered).reliable {
                    qos::reliable()
                } else {
                    qos::sensor_data()
                };
                node.raw_subscription(
                    &t.name,
                    &t.type_name,
                    profile.history(ros2_client::qos::History::KeepLast { depth: 200 }),
                )?
            };
            if let Some(b) = bridge.as_deref_mut() {
                if let Err(e) = b.advertise(&t.name, &t.type_name, definition) {
                    node.warn(format!("Foxglove channel for {}: {e}", t.name));
                }
            }
            let role = self.routes.role(&t.name, &t.type_name);
            node.info(format!(
                "reading {} ({}){}",
                t.name,
                t.type_name,
                if role == Role::Other {
                    ""
                } else {
                    " for the page"
                }
            ));
            self.subscriptions.push((sub, role));
        }
        Ok(())
    }

    /// Take every waiting message; returns how many there were.
    pub fn drain(
        &self,
        state: &Arc<Mutex<DashboardState>>,
        bridge: Option<&FoxgloveBridge>,
        node: &MetrocellNode,
    ) -> usize {
        let mut n = 0;
        for (sub, role) in &self.subscriptions {
            loop {
                let m = match sub.take() {
                    Ok(Some(m)) => m,
                    Ok(None) => break,
                    Err(e) => {
                        node.warn(e.to_string());
                        break;
                    }
                };
                n += 1;
                if let Some(b) = bridge {
                    b.forward(sub.topic(), &m);
                }
                if *role != Role::Other {
                    let mut s = state.lock().unwrap_or_else(|p| p.into_inner());
                    apply(&mut s, sub.topic(), role, &m);
                }
            }
        }
        n
    }
}

/// Decode `m` as the role's type and feed it to the state. What cannot be used is counted on
/// the page with its reason (undecodable here, bad fields by the state), never a panic.
fn apply(s: &mut DashboardState, topic: &str, role: &Role, m: &RawMessage) {
    let msg = SourcedMessage {
        topic: topic.to_string(),
        log_time_ns: m.receive_time_ns.max(0) as u64,
        publish_time_ns: m.source_time_ns.unwrap_or(m.receive_time_ns).max(0) as u64,
        payload: m.payload.clone(),
    };
    fn decoded<T: RosMessage>(s: &mut DashboardState, msg: &SourcedMessage) -> Option<T> {
        msg.decode::<T>()
            .map_err(|e| s.undecodable(&msg.topic, &e.to_string()))
            .ok()
    }
    // field errors are already counted by the state; nothing more to do with them here
    match role {
        Role::Points => {
            if let Some(p) = decoded::<MeasuredPoint>(s, &msg) {
                let _ = s.measured_point(topic, &p);
            }
        }
        Role::Model => {
            if let Some(v) = decoded::<ErrorModel>(s, &msg) {
                let _ = s.error_model(topic, &v);
            }
        }
        Role::Temperature(sensor) => {
            if let Some(t) = decoded::<Temperature>(s, &msg) {
                let _ = s.temperature(topic, sensor, &t);
            }
        }
        Role::Tracker => {
            if let Some(t) = decoded::<TrackerMeasurement>(s, &msg) {
                s.tracker(topic, &t);
            }
        }
        Role::Diagnostics => {
            if let Some(a) = decoded::<DiagnosticArray>(s, &msg) {
                s.diagnostics(topic, &a);
            }
        }
        Role::Clock => {
            if let Some(c) = decoded::<Clock>(s, &msg) {
                s.clock(topic, c.clock.nanos());
            }
        }
        Role::Other => {}
    }
}
