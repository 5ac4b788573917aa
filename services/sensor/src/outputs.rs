//! The sensor's publishers (DESIGN §4); the simulator's readings become wire
//! messages in [`nauta_sim::wire`].

use nauta_messages::*;
use nauta_runtime::{Context, PortDescription, Publisher, services};
use nauta_sim::suite::Measurements;

/// Every output of the sensor process.
pub struct Outputs {
    truth: Publisher<TruthState>,
    imu: Publisher<ImuSample>,
    ahrs: Publisher<AhrsSample>,
    dvl: Publisher<DvlSample>,
    depth: Publisher<DepthSample>,
    gps: Publisher<GpsFix>,
    propeller: Publisher<PropellerSample>,
    modem: Publisher<BuoyRange>,
    lbl: Publisher<LblReply>,
    /// `sensor/progress`: watermarks and the end of stream.
    pub progress: Publisher<Progress>,
    scratch: Vec<SensorMessage>,
}

/// The data outputs, for `--describe`.
pub fn describe() -> Vec<PortDescription> {
    vec![
        PortDescription::of(&services::imu()),
        PortDescription::of(&services::ahrs()),
        PortDescription::of(&services::dvl()),
        PortDescription::of(&services::depth()),
        PortDescription::of(&services::gps()),
        PortDescription::of(&services::propeller()),
        PortDescription::of(&services::modem()),
        PortDescription::of(&services::lbl_reply()),
        PortDescription::of(&services::truth()),
        PortDescription::of(&services::progress(Role::Sensor)),
    ]
}

impl Outputs {
    /// Opens every publisher.
    pub fn open(ctx: &Context) -> anyhow::Result<Self> {
        Ok(Self {
            truth: ctx.publisher(&services::truth())?,
            imu: ctx.publisher(&services::imu())?,
            ahrs: ctx.publisher(&services::ahrs())?,
            dvl: ctx.publisher(&services::dvl())?,
            depth: ctx.publisher(&services::depth())?,
            gps: ctx.publisher(&services::gps())?,
            propeller: ctx.publisher(&services::propeller())?,
            modem: ctx.publisher(&services::modem())?,
            lbl: ctx.publisher(&services::lbl_reply())?,
            progress: ctx.publisher(&services::progress(Role::Sensor))?,
            scratch: Vec::new(),
        })
    }

    /// Publishes one step's measurements, in [`nauta_sim::wire`]'s order (the
    /// truth first, LBL replies in stamp order).
    pub fn publish(&mut self, m: &Measurements) -> anyhow::Result<()> {
        let mut scratch = std::mem::take(&mut self.scratch);
        scratch.clear();
        nauta_sim::wire::to_wire(m, &mut scratch);
        let result = scratch.iter().try_for_each(|msg| self.publish_message(msg));
        self.scratch = scratch;
        result
    }

    /// Publishes one message as it is (its stamp and flags; the sequence,
    /// source and instance are this publisher's).
    pub fn publish_message(&mut self, msg: &SensorMessage) -> anyhow::Result<()> {
        match *msg {
            SensorMessage::Truth(m) => self.truth.publish(m)?,
            SensorMessage::Imu(m) => self.imu.publish(m)?,
            SensorMessage::Ahrs(m) => self.ahrs.publish(m)?,
            SensorMessage::Dvl(m) => self.dvl.publish(m)?,
            SensorMessage::Depth(m) => self.depth.publish(m)?,
            SensorMessage::Gps(m) => self.gps.publish(m)?,
            SensorMessage::Propeller(m) => self.propeller.publish(m)?,
            SensorMessage::Modem(m) => self.modem.publish(m)?,
            SensorMessage::Lbl(m) => self.lbl.publish(m)?,
        }
        Ok(())
    }

    /// Publishes a watermark (or the end of stream) and wakes everyone. The
    /// data services are flushed first: each attaches the subscribers that
    /// joined since its last send and hands them its history, so a consumer
    /// restarted meanwhile has the messages a watermark covers before the
    /// watermark itself (else it would refuse them as earlier than their
    /// publisher's watermark; in `sim` clock a sparse channel such as the
    /// modem's attached only at the next flush, after the batch's
    /// watermark).
    pub fn publish_watermark(&mut self, p: Progress) -> anyhow::Result<()> {
        self.flush();
        self.progress.publish_now(p)?;
        Ok(())
    }

    /// Wakes the subscribers of everything published since the last flush.
    pub fn flush(&mut self) {
        self.truth.flush();
        self.imu.flush();
        self.ahrs.flush();
        self.dvl.flush();
        self.depth.flush();
        self.gps.flush();
        self.propeller.flush();
        self.modem.flush();
        self.lbl.flush();
        self.progress.flush();
    }

    /// Data messages published (progress excluded).
    pub fn published(&self) -> u64 {
        self.truth.published()
            + self.imu.published()
            + self.ahrs.published()
            + self.dvl.published()
            + self.depth.published()
            + self.gps.published()
            + self.propeller.published()
            + self.modem.published()
            + self.lbl.published()
    }

    /// Deliveries given up on back-pressure deadlines.
    pub fn given_up(&self) -> u64 {
        self.truth.given_up()
            + self.imu.given_up()
            + self.ahrs.given_up()
            + self.dvl.given_up()
            + self.depth.given_up()
            + self.gps.given_up()
            + self.propeller.given_up()
            + self.modem.given_up()
            + self.lbl.given_up()
            + self.progress.given_up()
    }

    /// Per-service counts, for the log line at the end.
    pub fn counts(&self) -> Vec<(&str, u64)> {
        vec![
            (self.truth.service(), self.truth.published()),
            (self.imu.service(), self.imu.published()),
            (self.ahrs.service(), self.ahrs.published()),
            (self.dvl.service(), self.dvl.published()),
            (self.depth.service(), self.depth.published()),
            (self.gps.service(), self.gps.published()),
            (self.propeller.service(), self.propeller.published()),
            (self.modem.service(), self.modem.published()),
            (self.lbl.service(), self.lbl.published()),
        ]
    }
}
